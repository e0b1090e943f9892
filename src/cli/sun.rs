//! `radiosity sun`: shortwave light under the sun and an isotropic sky, per face and element,
//! for one sun or a day of sun positions (each solved on the same view factors).

use std::path::Path;
use std::time::Instant;

use serde::Serialize;

use radiosity::discretization::{Discretization, Method};
use radiosity::error::{Error, Result};
use radiosity::pipeline::{self, Problem};
use radiosity::report;
use radiosity::report::{Tone, UrbanExport, VFSPARSE_THRESHOLD};
use radiosity::scene::{Scene, stl_triangles};
use radiosity::shortwave::{Balance, Fluxes, Shortwave, shortwave};
use radiosity::solution::SolutionField;
use radiosity::solve::DEFAULT_TOLERANCE;
use radiosity::sun::{Moment, Sources, Sun, read_moments};
use radiosity::viewfactors::{ClosureOptions, ViewFactorOptions, view_factors};

use super::args::{SunArgs, parse_size};

/// What `sun --json` writes: the view factors' figures, then one sun's light (flattened) or,
/// with `--sun-positions`, each time's under `times`.
#[derive(Serialize)]
struct SunSummary<'a> {
    scene: &'a str,
    /// Elements.
    n: usize,
    faces: usize,
    /// The view factors' figures: null with `--direct-only`.
    view_factor_tolerance: Option<f64>,
    view_factor_error_estimate: Option<f64>,
    sky_view_factor_min: Option<f64>,
    sky_view_factor_max: Option<f64>,
    conditioned: bool,
    view_factor_seconds: f64,
    shortwave_seconds: f64,
    seconds: f64,
    /// The files `--export` wrote.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    exported: Vec<String>,
    #[serde(flatten)]
    light: Option<Light<'a>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    times: Option<Vec<Light<'a>>>,
}

/// One sun's light over the scene.
#[derive(Serialize)]
struct Light<'a> {
    #[serde(skip_serializing_if = "str::is_empty")]
    time: &'a str,
    sun: Sun,
    /// Unit vector towards the sun.
    direction: [f64; 3],
    diffuse_horizontal: f64,
    /// Σ of the elements' sunlit areas.
    sunlit_area: f64,
    /// Σ of the areas of the elements that face the sun.
    area_facing_sun: f64,
    #[serde(flatten)]
    balance: Balance,
    /// GMRES's products for the reflections.
    iterations: usize,
    seconds: f64,
}

impl<'a> Light<'a> {
    fn of(moment: &'a Moment, light: &Shortwave, seconds: f64) -> Self {
        let Sources { sun, diffuse_horizontal } = moment.sources;
        let elements = &light.elements;
        Self {
            time: &moment.time,
            sun,
            direction: sun.direction().into(),
            diffuse_horizontal,
            sunlit_area: elements.iter().map(|e| e.area * e.sunlit_fraction).sum(),
            area_facing_sun: elements
                .iter()
                .filter(|e| e.cos_incidence > 0.0)
                .map(|e| e.area)
                .sum(),
            balance: light.balance,
            iterations: light.iterations,
            seconds,
        }
    }
}

/// The moments the arguments ask for: the day of `--sun-positions`, the one sun of `--zenith`,
/// `--azimuth` and `--direct-normal` (clap requires the three together), or the scene file's
/// `[sun]` and `[sky]`.
fn moments(args: &SunArgs, scene: &Scene) -> Result<Vec<Moment>> {
    if let Some(path) = &args.sun_positions {
        return read_moments(Path::new(path), args.x_azimuth);
    }
    let sources = match (args.zenith, args.azimuth, args.direct_normal, &scene.daylight) {
        (Some(zenith), Some(azimuth), Some(direct_normal), _) => {
            let sun = Sun::new(zenith, azimuth, args.x_azimuth, direct_normal)?;
            Sources::new(sun, args.diffuse_horizontal.unwrap_or(0.0))?
        }
        (None, None, None, Some(daylight)) => {
            let mut daylight = *daylight;
            if let Some(d) = args.diffuse_horizontal {
                daylight.diffuse_horizontal = d;
            }
            Sources::of_daylight(&daylight)?
        }
        _ => {
            return Err(Error::InvalidParameter {
                name: "sun",
                value: scene.name.clone(),
                reason: "give --zenith, --azimuth and --direct-normal, --sun-positions FILE, or \
                         a [sun] table in the scene file"
                    .into(),
            });
        }
    };
    Ok(vec![Moment { time: String::new(), sources }])
}

pub(crate) fn run_sun(args: &SunArgs) -> Result<()> {
    let options = ViewFactorOptions { tolerance: args.tolerance, ..Default::default() };
    options.validate()?;
    for (flag, path) in [("csv", &args.csv), ("element-csv", &args.element_csv)] {
        if let Some(path) = path.as_deref().filter(|p| !p.ends_with(".csv")) {
            return Err(Error::InvalidParameter {
                name: flag,
                value: path.into(),
                reason: "expected a .csv file".into(),
            });
        }
    }
    let started = Instant::now();
    let config = args.scene.config()?;
    let problem = pipeline::build(&config)?;
    let Problem { scene, mesh, planner, .. } = &problem;
    let moments = moments(args, scene)?;
    if args.export.is_some() && args.sun_positions.is_some() {
        // timedepsw.inp numbers its times: refused now, not after the work.
        report::timedepsw_seconds(moments.iter().map(|m| m.time.as_str()))?;
    }
    super::output::print_notes(scene);
    // Which element each exported facet is, settled before the work.
    let facets = match &args.export {
        Some(_) if args.scene.refine != 0 => {
            return Err(Error::InvalidParameter {
                name: "export",
                value: format!("--refine {}", args.scene.refine),
                reason: "the files hold one value per facet: give --refine 0".into(),
            });
        }
        Some(_) => {
            let stl = args.scene.scene.to_ascii_lowercase().ends_with(".stl");
            let triangles = stl.then(|| stl_triangles(Path::new(&args.scene.scene))).transpose()?;
            Some(report::facet_elements(scene, mesh, triangles.as_deref())?)
        }
        None => None,
    };
    let closure = match facets {
        Some(_) => ClosureOptions { condition: true, drop_below: Some(VFSPARSE_THRESHOLD) },
        None => ClosureOptions { condition: args.condition, drop_below: None },
    };
    if args.direct_only && moments.iter().any(|m| m.sources.diffuse_horizontal > 0.0) {
        eprintln!("note: --direct-only leaves out the sky: the diffuse irradiances are not used");
    }
    let f = if args.direct_only {
        None
    } else {
        let progress = super::progress::on_stderr();
        progress.start("viewfactors", mesh.len());
        let mut f = view_factors(scene, mesh, planner, &options, &*progress)?;
        progress.finish();
        f.close(&closure)?;
        Some(f)
    };
    let view_factor_seconds = started.elapsed().as_secs_f64();
    let mut lights = Vec::with_capacity(moments.len());
    for moment in &moments {
        let t = Instant::now();
        let light = shortwave(scene, mesh, f.as_ref(), &moment.sources, DEFAULT_TOLERANCE)?;
        lights.push((light, t.elapsed().as_secs_f64()));
    }
    let exported = match (&facets, &args.export) {
        (Some(facets), Some(dir)) => {
            let times = moments.iter().zip(&lights).map(|(m, (l, _))| (m.time.as_str(), l));
            let export = UrbanExport {
                dir: Path::new(dir),
                expnr: args.expnr.as_deref(),
                facets,
                view_factors: f.as_ref(),
                times: times.collect(),
            };
            export.write()?.iter().map(|p| p.display().to_string()).collect()
        }
        _ => Vec::new(),
    };
    let seconds = started.elapsed().as_secs_f64();
    let sky = f.as_ref().map(|f| f.sky_view_factors());
    let one = moments.len() == 1 && args.sun_positions.is_none();
    let mut summaries = moments
        .iter()
        .zip(&lights)
        .map(|(m, (light, s))| Light::of(m, light, *s))
        .collect::<Vec<_>>();
    let summary = SunSummary {
        scene: &scene.name,
        n: mesh.len(),
        faces: scene.faces.len(),
        view_factor_tolerance: f.as_ref().map(|_| args.tolerance),
        view_factor_error_estimate: f.as_ref().map(|f| f.error_estimate),
        sky_view_factor_min: sky.as_ref().map(|s| s.iter().copied().fold(f64::INFINITY, f64::min)),
        sky_view_factor_max: sky
            .as_ref()
            .map(|s| s.iter().copied().fold(f64::NEG_INFINITY, f64::max)),
        conditioned: closure.condition,
        view_factor_seconds,
        shortwave_seconds: seconds - view_factor_seconds,
        seconds,
        exported,
        light: if one { summaries.pop() } else { None },
        times: if one { None } else { Some(summaries) },
    };
    if let Some(path) = &args.csv {
        let rows = moments.iter().zip(&lights).flat_map(|(m, (light, _))| {
            let names = scene.faces.iter().map(|f| f.name.as_str());
            let faces = light.by_face(mesh);
            names.zip(faces).enumerate().map(move |(k, (name, f))| (m.time.as_str(), k, name, f))
        });
        write_csv(path, "face,name", !one, rows)?;
    }
    if let Some(path) = &args.element_csv {
        let rows = moments.iter().zip(&lights).flat_map(|(m, (light, _))| {
            let names = mesh.elements().iter().map(|e| scene.faces[e.face].name.as_str());
            names
                .zip(light.elements.iter().copied())
                .enumerate()
                .map(move |(k, (name, f))| (m.time.as_str(), k, name, f))
        });
        write_csv(path, "element,face", !one, rows)?;
    }
    if let Some(path) = &args.vtu {
        let elements = &lights[0].0.elements;
        let fields: Vec<(&str, Vec<f64>)> = Fluxes::COLUMNS
            .iter()
            .enumerate()
            .map(|(k, &name)| (name, elements.iter().map(|e| e.values()[k]).collect()))
            .collect();
        report::write_cell_vtu(scene, mesh, &fields, Path::new(path))?;
    }
    if let Some(path) = &args.png {
        let time = &moments[0].time;
        let title = format!(
            "{}: absorbed shortwave{}{time}",
            scene.name,
            if time.is_empty() { "" } else { " at " }
        );
        write_picture(
            &problem,
            &lights[0].0,
            &title,
            parse_size("png-size", &args.png_size)?,
            path,
        )?;
    }
    if let Some(target) = &args.json {
        return report::write_json(&summary, target);
    }
    print_summary(&summary, &lights[0].0, scene, mesh);
    for path in &summary.exported {
        println!("wrote {path}");
    }
    Ok(())
}

/// The scene coloured by each element's absorbed flux, into the PNG at `path`.
fn write_picture(
    problem: &Problem,
    light: &Shortwave,
    title: &str,
    size: (u32, u32),
    path: &str,
) -> Result<()> {
    let Problem { scene, mesh, .. } = problem;
    let disc = Discretization::new(scene, mesh, Method::Centroid)?;
    let absorbed: Vec<f64> = light.elements.iter().map(|e| e.absorbed).collect();
    let none = vec![0.0; absorbed.len()];
    let field = SolutionField {
        scene,
        mesh,
        disc: &disc,
        u: &absorbed,
        emission: &none,
        bands: &[],
        cases: &[],
    };
    let camera = report::Camera::default_view(&field, glam::DVec3::Z);
    let quantity = "absorbed (W/m2)";
    report::render_png(&field, &camera, size, (title, quantity), Tone::Linear, Path::new(path))
}

/// One row per face or element (and time, where `timed`): its index and its face's name
/// (`columns`: "face,name" or "element,face"), then its fluxes.
fn write_csv<'a>(
    path: &str,
    columns: &str,
    timed: bool,
    rows: impl Iterator<Item = (&'a str, usize, &'a str, Fluxes)>,
) -> Result<()> {
    let time = if timed { "time," } else { "" };
    let mut text = format!("{time}{columns},{}\n", Fluxes::COLUMNS.join(","));
    for (time, k, name, f) in rows {
        if timed {
            text.push_str(time);
            text.push(',');
        }
        let values: Vec<String> = f.values().iter().map(|v| format!("{v:e}")).collect();
        text.push_str(&format!("{k},{name},{}\n", values.join(",")));
    }
    std::fs::write(path, text)?;
    Ok(())
}

/// The summary as text: one sun's figures and, for scenes of at most 12 faces, each face's
/// fluxes; or a line per time of a day.
fn print_summary(s: &SunSummary, first: &Shortwave, scene: &Scene, mesh: &radiosity::mesh::Mesh) {
    println!(
        "{}: n = {} elements on {} faces, {:.2} s (view factors {:.2} s, light {:.2} s)",
        s.scene, s.n, s.faces, s.seconds, s.view_factor_seconds, s.shortwave_seconds
    );
    if let (Some(t), Some(e), Some(lo), Some(hi)) = (
        s.view_factor_tolerance,
        s.view_factor_error_estimate,
        s.sky_view_factor_min,
        s.sky_view_factor_max,
    ) {
        let conditioned = if s.conditioned { ", conditioned" } else { "" };
        println!(
            "view factors: tolerance {t:.0e}, estimate {e:.2e}{conditioned}; sky view factors \
             {lo:.6} .. {hi:.6}"
        );
    } else {
        println!("direct sunlight alone (--direct-only): no sky, reflections not followed");
    }
    let share = |l: &Light| {
        if l.area_facing_sun > 0.0 { 100.0 * l.sunlit_area / l.area_facing_sun } else { 0.0 }
    };
    if let Some(times) = &s.times {
        println!(
            "{:>10} {:>8} {:>8} {:>8} {:>12} {:>12} {:>12} {:>8} {:>4}",
            "time",
            "zenith",
            "azimuth",
            "sunlit%",
            "received",
            "absorbed",
            "escaped",
            "balance",
            "its"
        );
        for l in times {
            let b = &l.balance;
            println!(
                "{:>10} {:>8.3} {:>8.3} {:>8.2} {:>12.6e} {:>12.6e} {:>12.6e} {:>8.1e} {:>4}",
                l.time,
                l.sun.zenith,
                l.sun.azimuth,
                share(l),
                b.received,
                b.absorbed,
                b.escaped,
                b.relative_gap,
                l.iterations
            );
        }
        return;
    }
    let Some(l) = &s.light else { return };
    let [x, y, z] = l.direction;
    println!(
        "sun: zenith {} deg, azimuth {} deg (+x at {} deg), direction ({x:.6}, {y:.6}, {z:.6}), \
         direct normal {}; sky: diffuse horizontal {}",
        l.sun.zenith, l.sun.azimuth, l.sun.x_azimuth, l.sun.direct_normal, l.diffuse_horizontal
    );
    println!(
        "sunlit: {:.6e} of the {:.6e} facing the sun ({:.2} %)",
        l.sunlit_area,
        l.area_facing_sun,
        share(l)
    );
    let b = &l.balance;
    println!(
        "power: received from sun and sky {:.6e}, absorbed {:.6e}, escaped to the sky {:.6e} \
         (balance {:.1e} relative); reflections by GMRES in {} products",
        b.received, b.absorbed, b.escaped, b.relative_gap, l.iterations
    );
    if scene.faces.len() <= 12 {
        println!(
            "{:>12} {:>8} {:>8} {:>10} {:>10} {:>10} {:>10} {:>10}",
            "face", "sunlit", "svf", "direct", "sky", "reflected", "absorbed", "outgoing"
        );
        for (face, f) in scene.faces.iter().zip(first.by_face(mesh)) {
            println!(
                "{:>12} {:>8.4} {:>8.4} {:>10.3} {:>10.3} {:>10.3} {:>10.3} {:>10.3}",
                face.name,
                f.sunlit_fraction,
                f.sky_view_factor,
                f.direct,
                f.sky,
                f.reflected,
                f.absorbed,
                f.outgoing
            );
        }
    }
}
