//! clap's parser for the library's named options: the values accepted, their help lines and
//! the error for a name not known all come from the library's tables
//! ([`radiosity::vocabulary::Named`]).

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use radiosity::vocabulary::Named;

/// The parser of `T`'s names: `#[arg(long, value_parser = named::<T>())]`.
pub(crate) fn named<T: Named + Send + Sync>() -> impl TypedValueParser<Value = T> {
    let values = T::CHOICES.iter().map(|c| PossibleValue::new(c.name).help(c.help.trim()));
    PossibleValuesParser::new(values)
        .map(|name: String| T::parse(&name).expect("clap accepts the table's names only"))
}
