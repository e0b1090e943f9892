//! `radiosity sun`: shortwave light under the sun and an isotropic sky, per face and element.

use serde::Serialize;

use radiosity::error::{Error, Result};
use radiosity::pipeline::{self, Problem};
use radiosity::report;
use radiosity::scene::Scene;
use radiosity::shortwave::{Balance, Fluxes, Sources, shortwave};
use radiosity::solve::DEFAULT_TOLERANCE;
use radiosity::sun::Sun;
use radiosity::viewfactors::{ClosureOptions, ViewFactorOptions, view_factors};

use super::args::SunArgs;

/// What `sun --json` writes.
#[derive(Serialize)]
struct SunSummary<'a> {
    scene: &'a str,
    /// Elements.
    n: usize,
    faces: usize,
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
    view_factor_tolerance: f64,
    view_factor_error_estimate: f64,
    sky_view_factor_min: f64,
    sky_view_factor_max: f64,
    conditioned: bool,
    view_factor_seconds: f64,
    shortwave_seconds: f64,
    seconds: f64,
}

pub(crate) fn run_sun(args: &SunArgs) -> Result<()> {
    let sun = Sun::new(args.zenith, args.azimuth, args.x_azimuth, args.direct_normal)?;
    let sources = Sources::new(sun, args.diffuse_horizontal)?;
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
    let started = std::time::Instant::now();
    let config = args.scene.config()?;
    let problem = pipeline::build(&config)?;
    let Problem { scene, mesh, planner, .. } = &problem;
    super::output::print_notes(scene);
    let progress = super::progress::on_stderr();
    progress.start("viewfactors", mesh.len());
    let mut f = view_factors(scene, mesh, planner, &options, &*progress)?;
    progress.finish();
    f.close(&ClosureOptions { condition: args.condition, drop_below: None })?;
    let view_factor_seconds = started.elapsed().as_secs_f64();
    let light = shortwave(scene, mesh, &f, &sources, DEFAULT_TOLERANCE)?;
    let seconds = started.elapsed().as_secs_f64();
    let elements = &light.elements;
    let sky = elements.iter().map(|e| e.sky_view_factor);
    let summary = SunSummary {
        scene: &scene.name,
        n: mesh.len(),
        faces: scene.faces.len(),
        sun,
        direction: sun.direction().into(),
        diffuse_horizontal: args.diffuse_horizontal,
        sunlit_area: elements.iter().map(|e| e.area * e.sunlit_fraction).sum(),
        area_facing_sun: elements.iter().filter(|e| e.cos_incidence > 0.0).map(|e| e.area).sum(),
        balance: light.balance,
        iterations: light.iterations,
        view_factor_tolerance: args.tolerance,
        view_factor_error_estimate: f.error_estimate,
        sky_view_factor_min: sky.clone().fold(f64::INFINITY, f64::min),
        sky_view_factor_max: sky.fold(f64::NEG_INFINITY, f64::max),
        conditioned: args.condition,
        view_factor_seconds,
        shortwave_seconds: seconds - view_factor_seconds,
        seconds,
    };
    let faces = light.by_face(mesh);
    if let Some(path) = &args.csv {
        let names = scene.faces.iter().map(|f| f.name.as_str());
        write_csv(path, "face,name", names.zip(&faces))?;
    }
    if let Some(path) = &args.element_csv {
        let names = mesh.elements().iter().map(|e| scene.faces[e.face].name.as_str());
        write_csv(path, "element,face", names.zip(elements))?;
    }
    if let Some(target) = &args.json {
        return report::write_json(&summary, target);
    }
    print_summary(&summary, &faces, scene);
    Ok(())
}

/// One row per face or element: its index and its face's name (`columns`: "face,name" or
/// "element,face"), then its fluxes.
fn write_csv<'a>(
    path: &str,
    columns: &str,
    rows: impl Iterator<Item = (&'a str, &'a Fluxes)>,
) -> Result<()> {
    let mut text = format!(
        "{columns},area,sunlit_fraction,cos_incidence,sky_view_factor,direct,sky,\
         reflected,absorbed,outgoing\n"
    );
    for (k, (name, f)) in rows.enumerate() {
        text.push_str(&format!(
            "{k},{name},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}\n",
            f.area,
            f.sunlit_fraction,
            f.cos_incidence,
            f.sky_view_factor,
            f.direct,
            f.sky,
            f.reflected,
            f.absorbed,
            f.outgoing
        ));
    }
    std::fs::write(path, text)?;
    Ok(())
}

/// The summary as text, and each face's fluxes for scenes of at most 12 faces.
fn print_summary(s: &SunSummary, faces: &[Fluxes], scene: &Scene) {
    println!(
        "{}: n = {} elements on {} faces, {:.2} s (view factors {:.2} s, light {:.2} s)",
        s.scene, s.n, s.faces, s.seconds, s.view_factor_seconds, s.shortwave_seconds
    );
    let [x, y, z] = s.direction;
    println!(
        "sun: zenith {} deg, azimuth {} deg (+x at {} deg), direction ({x:.6}, {y:.6}, {z:.6}), \
         direct normal {}; sky: diffuse horizontal {}",
        s.sun.zenith, s.sun.azimuth, s.sun.x_azimuth, s.sun.direct_normal, s.diffuse_horizontal
    );
    println!(
        "sunlit: {:.6e} of the {:.6e} facing the sun ({:.2} %)",
        s.sunlit_area,
        s.area_facing_sun,
        if s.area_facing_sun > 0.0 { 100.0 * s.sunlit_area / s.area_facing_sun } else { 0.0 }
    );
    let b = &s.balance;
    println!(
        "power: received from sun and sky {:.6e}, absorbed {:.6e}, escaped to the sky {:.6e} \
         (balance {:.1e} relative); reflections by GMRES in {} products",
        b.received, b.absorbed, b.escaped, b.relative_gap, s.iterations
    );
    println!(
        "view factors: tolerance {:.0e}, estimate {:.2e}{}; sky view factors {:.6} .. {:.6}",
        s.view_factor_tolerance,
        s.view_factor_error_estimate,
        if s.conditioned { ", conditioned" } else { "" },
        s.sky_view_factor_min,
        s.sky_view_factor_max
    );
    if faces.len() <= 12 {
        println!(
            "{:>12} {:>8} {:>8} {:>10} {:>10} {:>10} {:>10} {:>10}",
            "face", "sunlit", "svf", "direct", "sky", "reflected", "absorbed", "outgoing"
        );
        for (face, f) in scene.faces.iter().zip(faces) {
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
