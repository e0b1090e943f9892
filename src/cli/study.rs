//! `radiosity study`: the paper's tables and figures, and the stability studies.

use radiosity::error::{Error, Result};
use radiosity::pipeline::{BackendName, SceneSource};
use radiosity::report;
use radiosity::report::TableFormat;
use radiosity::study::cities::{CitySeries, SIZES, run_cities};
use radiosity::study::compression::{CompressionSeries, TOLERANCES, run_compression};
use radiosity::study::estimates::{
    DEFAULT_SEEDS, EstimateSeries, TOLERANCES as ESTIMATE_TOLERANCES, run_estimates,
};
use radiosity::study::{StudyDevice, StudyOptions};

use super::args::StudyArgs;
use super::output::emit;
use super::ranks::{is_root, world};

/// Runs the study `args.id` and prints it (JSON to `--json` when given, and the table unless
/// the JSON goes to standard output); plots go to `--figures`.
pub(crate) fn run(args: &StudyArgs) -> Result<()> {
    let StudyArgs { id, max_n, backend: device, precision, figures, markdown, .. } = args;
    let (id, max_n, markdown) = (id.as_str(), *max_n, *markdown);
    let json = args.json.as_deref();
    let given = [
        ("scene", !args.scene.is_empty(), &["compression", "estimates"][..]),
        ("tolerances", args.tolerances.is_some(), &["compression", "estimates"]),
        ("shadowed-blocks", args.shadowed_blocks, &["compression"]),
        ("seeds", args.seeds.is_some(), &["estimates"]),
    ];
    if let Some((flag, _, owners)) =
        given.iter().find(|(_, given, owners)| *given && !owners.contains(&id))
    {
        return Err(Error::InvalidParameter {
            name: flag,
            value: id.to_string(),
            reason: format!("--{flag} belongs to study {}", owners.join(" and study ")),
        });
    }
    if id == "compression" && args.scene.len() > 1 {
        return Err(Error::InvalidParameter {
            name: "scene",
            value: args.scene.join(", "),
            reason: "study compression runs on one scene".into(),
        });
    }
    let device = match *device {
        None => StudyDevice::Auto,
        Some(BackendName::Cpu) => StudyDevice::Cpu,
        Some(BackendName::Gpu) => StudyDevice::Gpu(*precision),
    };
    let format = if markdown { TableFormat::Markdown } else { TableFormat::Text };
    match id {
        "stability" => {
            let result = radiosity::study::stability::run_stability(device)?;
            emit(&result, json, || report::stability_table(&result, format))
        }
        "compression" => {
            let progress =
                if is_root() { super::progress::on_stderr() } else { Default::default() };
            // The study measures the CPU unless the GPU is asked for.
            let backend = match device {
                StudyDevice::Gpu(p) => radiosity::pipeline::Backend::Gpu(p),
                _ => radiosity::pipeline::Backend::Cpu,
            };
            let ranks = world();
            let series = CompressionSeries {
                scene: args.scene.first().map(|s| SceneSource::parse(s)).transpose()?,
                max_n,
                tolerances: args.tolerances.clone().unwrap_or(TOLERANCES.to_vec()),
                shadowed_blocks: args.shadowed_blocks,
            };
            let mut result = run_compression(&series, backend, &progress, ranks.as_ref())?;
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
            let result = radiosity::study::stability::run_stiff(device)?;
            emit(&result, json, || report::stiff_table(&result, format))
        }
        _ => {
            let options = StudyOptions { max_n, device, progress: super::progress::on_stderr() };
            let mut result = radiosity::study::run_study(id, &options)?;
            result.figures = report::write_study_figures(&result, std::path::Path::new(figures))?;
            emit(&result, json, || report::study_table(&result, format))
        }
    }
}
