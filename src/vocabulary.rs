//! The names users type for the options with a fixed set of values (`--mesh uniform`,
//! `method="linear"`): one table per option, declared with its enum by [`named_options!`], so
//! that parsing, display, the command line's help and the Python layer's vocabulary all read
//! the same table. A new value is one variant and its doc line.

use crate::error::{Error, Result};

/// One value of an option: its name and the help line users see beside it.
#[derive(Clone, Copy, Debug)]
pub struct Choice<T> {
    /// The value.
    pub value: T,
    /// Its name, as typed.
    pub name: &'static str,
    /// What it means, in one line (the variant's doc comment).
    pub help: &'static str,
}

/// An option whose values are named.
pub trait Named: Copy + PartialEq + Sized + 'static {
    /// The option's name (`mesh`, `shadow-lines`), as errors name it.
    const OPTION: &'static str;
    /// Every value, in the order help lists them.
    const CHOICES: &'static [Choice<Self>];

    /// The value's name.
    fn name(self) -> &'static str {
        let choice = Self::CHOICES.iter().find(|c| c.value == self);
        choice.expect("named_options! names every variant").name
    }

    /// The value named `text`, or an error listing the names accepted.
    fn parse(text: &str) -> Result<Self> {
        match Self::CHOICES.iter().find(|c| c.name == text) {
            Some(choice) => Ok(choice.value),
            None => Err(Error::UnknownName {
                kind: Self::OPTION,
                name: text.into(),
                expected: Self::names().collect::<Vec<_>>().join(", "),
            }),
        }
    }

    /// The names accepted, in order.
    fn names() -> impl Iterator<Item = &'static str> {
        Self::CHOICES.iter().map(|c| c.name)
    }
}

/// Declares an enum of unit variants whose values users name, and its [`Named`] table: each
/// variant is written `Variant = "name"` under its doc comment, which becomes the value's help
/// line; `Variant = "name" default` makes it the `#[default]` of a `Default` derived. `Display`,
/// `FromStr` and an inherent `name()` come with it.
macro_rules! named_options {
    (
        $(#[$meta:meta])*
        $vis:vis enum $Type:ident as $option:literal {
            $( $(#[doc = $doc:literal])* $Variant:ident = $name:literal $($default:ident)?, )+
        }
    ) => {
        $(#[$meta])*
        $vis enum $Type {
            $( $(#[doc = $doc])* $(#[$default])? $Variant, )+
        }

        impl $crate::vocabulary::Named for $Type {
            const OPTION: &'static str = $option;
            const CHOICES: &'static [$crate::vocabulary::Choice<Self>] = &[
                $( $crate::vocabulary::Choice {
                    value: Self::$Variant,
                    name: $name,
                    help: concat!($($doc),*),
                }, )+
            ];
        }

        impl $Type {
            /// The value's name, as users type it.
            $vis fn name(self) -> &'static str {
                $crate::vocabulary::Named::name(self)
            }
        }

        impl ::std::fmt::Display for $Type {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str($crate::vocabulary::Named::name(*self))
            }
        }

        impl ::std::str::FromStr for $Type {
            type Err = $crate::error::Error;
            fn from_str(text: &str) -> $crate::error::Result<Self> {
                <Self as $crate::vocabulary::Named>::parse(text)
            }
        }
    };
}

pub(crate) use named_options;

named_options! {
    /// Floating-point precision: of a GPU kernel (f64 needs `SHADER_F64` and uses software
    /// transcendentals), of a matrix kept on the device (`--storage`), of the compressed
    /// operator's stored values.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
    #[serde(rename_all = "lowercase")]
    pub enum Precision as "precision" {
        /// Double precision
        F64 = "f64",
        /// Single precision
        F32 = "f32",
    }
}

impl Precision {
    /// Bytes per real number.
    pub fn bytes(self) -> usize {
        match self {
            Self::F64 => 8,
            Self::F32 => 4,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    crate::vocabulary::named_options! {
        /// A test option.
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
        enum Side as "side" {
            /// The left one,
            /// over two lines.
            Left = "left",
            /// The right one.
            Right = "right-hand" default,
        }
    }

    #[test]
    fn names_parse_display_and_help_come_from_one_table() {
        assert_eq!(Side::parse("right-hand").unwrap(), Side::Right);
        assert_eq!(Side::Left.to_string(), "left");
        assert_eq!(Side::Right.name(), "right-hand");
        assert_eq!(Side::default(), Side::Right);
        assert_eq!("left".parse::<Side>().unwrap(), Side::Left);
        assert_eq!(Side::names().collect::<Vec<_>>(), ["left", "right-hand"]);
        assert_eq!(Side::CHOICES[0].help.trim(), "The left one, over two lines.");
        let e = Side::parse("Right").unwrap_err().to_string();
        assert!(e.contains("side 'Right'") && e.contains("left, right-hand"), "{e}");
    }
}
