//! `radiosity study`: the paper's tables and figures, and the stability studies.

use clap::CommandFactory;
use radiosity::error::{Error, Result};
use radiosity::gpu::Precision;
use radiosity::pipeline::{Backend, SceneSource};
use radiosity::report;
use radiosity::report::TableFormat;
use radiosity::study::StudyOptions;
use radiosity::study::cities::{CitySeries, SIZES, run_cities};
use radiosity::study::compression::{CompressionSeries, TOLERANCES, run_compression};
use radiosity::study::estimates::{
    DEFAULT_SEEDS, EstimateSeries, TOLERANCES as ESTIMATE_TOLERANCES, run_estimates,
};

use super::args::{DEFAULT_FIGURES, StudyArgs};
use super::output::emit;
use super::ranks::{is_root, world};

/// The studies that take options of their own; every other id is one of the paper's tables or
/// figures (or error-vs-time, grading: `study::run_study`), named "paper" in [`OPTION_OWNERS`].
const OWN_STUDIES: [&str; 5] = ["compression", "estimates", "cities", "stability", "stiff"];

/// The options of `study` that only some studies take, the studies that take them (every
/// study takes `--json` and `--markdown`) and whether the arguments give it: the one table that
/// both the refusal of an option a study does not take and each study's `--help` read.
type OptionOwners = (&'static str, &'static [&'static str], fn(&StudyArgs) -> bool);
const OPTION_OWNERS: [OptionOwners; 8] = [
    ("max-n", &["paper", "compression", "cities"], |a| a.max_n.is_some()),
    ("backend", &["paper", "compression", "stability", "stiff"], |a| a.backend.is_some()),
    ("precision", &["paper", "compression", "stability", "stiff"], |a| a.precision.is_some()),
    ("figures", &["paper", "compression"], |a| a.figures.is_some()),
    ("scene", &["compression", "estimates"], |a| !a.scene.is_empty()),
    ("tolerances", &["compression", "estimates"], |a| a.tolerances.is_some()),
    ("seeds", &["estimates"], |a| a.seeds.is_some()),
    ("shadowed-blocks", &["compression"], |a| a.shadowed_blocks),
];

/// The study `id`'s name in [`OPTION_OWNERS`].
fn owner_name(id: &str) -> &str {
    OWN_STUDIES.into_iter().find(|&own| own == id).unwrap_or("paper")
}

/// The options of `study` that the study `id` does not take.
fn options_not_taken(id: &str) -> impl Iterator<Item = OptionOwners> {
    let owner = owner_name(id).to_string();
    OPTION_OWNERS.into_iter().filter(move |(_, owners, _)| !owners.contains(&owner.as_str()))
}

/// Runs the study `args.id` and prints it (JSON to `--json` when given, and the table unless
/// the JSON goes to standard output); plots go to `--figures`.
pub(crate) fn run(args: &StudyArgs) -> Result<()> {
    let StudyArgs { id, max_n, backend, markdown, .. } = args;
    let (id, max_n, markdown) = (id.as_str(), *max_n, *markdown);
    let json = args.json.as_deref();
    if let Some((flag, owners, _)) = options_not_taken(id).find(|(_, _, given)| given(args)) {
        let owners: Vec<String> = owners
            .iter()
            .map(|&o| {
                if o == "paper" {
                    "the paper's tables and figures".into()
                } else {
                    format!("study {o}")
                }
            })
            .collect();
        return Err(Error::InvalidParameter {
            name: flag,
            value: id.to_string(),
            reason: format!("--{flag} belongs to {}", owners.join(" and ")),
        });
    }
    let precision = args.precision.unwrap_or(Precision::F64);
    let figures = args.figures.as_deref().unwrap_or(DEFAULT_FIGURES);
    if id == "compression" && args.scene.len() > 1 {
        return Err(Error::InvalidParameter {
            name: "scene",
            value: args.scene.join(", "),
            reason: "study compression runs on one scene".into(),
        });
    }
    let backend = backend.map(|name| Backend::named(name, precision));
    let format = if markdown { TableFormat::Markdown } else { TableFormat::Text };
    match id {
        "stability" => {
            let result = radiosity::study::stability::run_stability(backend)?;
            emit(&result, json, || report::stability_table(&result, format))
        }
        "compression" => {
            let progress =
                if is_root() { super::progress::on_stderr() } else { Default::default() };
            // The study measures the CPU unless the GPU is asked for.
            let ranks = world();
            let series = CompressionSeries {
                scene: args.scene.first().map(|s| SceneSource::parse(s)).transpose()?,
                max_n,
                tolerances: args.tolerances.clone().unwrap_or(TOLERANCES.to_vec()),
                shadowed_blocks: args.shadowed_blocks,
            };
            let mut result = run_compression(
                &series,
                backend.unwrap_or(Backend::Cpu),
                &progress,
                ranks.as_ref(),
            )?;
            // Every rank ran the compressed operators; rank 0 holds the rows and prints them.
            if !is_root() {
                return Ok(());
            }
            result.figures =
                report::write_compression_figure(&result, std::path::Path::new(figures))?;
            emit(&result, json, || report::compression_table(&result, format))
        }
        "estimates" => {
            let mut scenes: Vec<SceneSource> =
                args.scene.iter().map(|s| SceneSource::parse(s)).collect::<Result<_>>()?;
            if scenes.is_empty() {
                scenes.push(SceneSource::City(4, 4, false));
            }
            let series = EstimateSeries {
                seeds: args.seeds.unwrap_or(DEFAULT_SEEDS),
                tolerances: args.tolerances.clone().unwrap_or(ESTIMATE_TOLERANCES.to_vec()),
                scenes,
            };
            let result = run_estimates(&series, &*super::progress::on_stderr())?;
            emit(&result, json, || report::estimate_table(&result, format))
        }
        "cities" => {
            let series = CitySeries { sizes: SIZES.to_vec(), max_n };
            let result = run_cities(&series, &*super::progress::on_stderr())?;
            emit(&result, json, || report::city_table(&result, format))
        }
        "stiff" => {
            let result = radiosity::study::stability::run_stiff(backend)?;
            emit(&result, json, || report::stiff_table(&result, format))
        }
        _ => {
            let options = StudyOptions { max_n, backend, progress: super::progress::on_stderr() };
            let mut result = radiosity::study::run_study(id, &options)?;
            result.figures = report::write_study_figures(&result, std::path::Path::new(figures))?;
            emit(&result, json, || report::study_table(&result, format))
        }
    }
}

/// `radiosity study ID --help` (or `-h`): `study`'s help with only the options that the study
/// ID takes; `None` where the arguments (`argv`, the program's name first) ask for anything
/// else, which clap then parses as usual.
pub(crate) fn help_for_one_study(argv: &[String]) -> Option<String> {
    let [_, command, id, rest @ ..] = argv else { return None };
    let long = rest.iter().any(|a| a == "--help");
    if command != "study" || id.starts_with('-') || !(long || rest.iter().any(|a| a == "-h")) {
        return None;
    }
    let mut study = super::Cli::command().find_subcommand("study")?.clone();
    for (flag, _, _) in options_not_taken(id) {
        study = study.mut_arg(flag.replace('-', "_"), |arg| arg.hide(true));
    }
    let mut study = study
        .mut_arg("id", |arg| arg.hide(true))
        .override_usage(format!("radiosity study {id} [OPTIONS]"));
    let help = if long { study.render_long_help() } else { study.render_help() };
    Some(help.to_string())
}
