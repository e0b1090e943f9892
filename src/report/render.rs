//! A false-colour picture of a solution, rendered headlessly by a small software rasterizer
//! (perspective camera, depth buffer, back faces culled so that a closed room seen from outside
//! shows its inside), with a colour bar drawn by plotters and encoded as PNG. With red, green and
//! blue bands solved, the picture is in colour: each band's u through the same tone map.

use std::path::Path;

use glam::{DVec2, DVec3};
use plotters::prelude::*;

use super::plot::{plot_error, register_font};
use crate::error::{Error, Result};
use crate::solution::SolutionField;

/// Where the picture is taken from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: DVec3,
    /// Point looked at (the centre of the picture).
    pub target: DVec3,
    /// Vertical field of view, degrees.
    pub fov_degrees: f64,
    /// The direction that is up in the picture (unit).
    pub up: DVec3,
}

/// Vertical field of view of the default cameras, degrees.
const FOV_DEGREES: f64 = 40.0;

impl Camera {
    /// A view of the whole scene from `direction` (from the scene's centre toward the eye),
    /// far enough that its bounding sphere fits the picture, with `up` (non-zero) up.
    pub fn overview(field: &SolutionField, direction: DVec3, up: DVec3) -> Self {
        let (lo, hi) = field.scene.faces.iter().map(|f| f.bounding_box()).fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), (a, b)| (lo.min(a), hi.max(b)),
        );
        let centre = 0.5 * (lo + hi);
        let radius = 0.5 * (hi - lo).length();
        let distance = radius / (0.5 * FOV_DEGREES.to_radians()).sin();
        Self {
            eye: centre + direction.normalize() * distance,
            target: centre,
            fov_degrees: FOV_DEGREES,
            up: up.normalize(),
        }
    }

    /// The default view with `up` (non-zero) up. The scene's frame is z-up turned so that z goes
    /// to `up` (x and y: the shortest turn; y-up OBJ files: x right, z toward the viewer). If a
    /// side of the scene's box is open (inward-facing faces cover less than half of it; tried
    /// toward the viewer first: -y, -x, +x, +y of that frame), the camera looks level through it
    /// at the centre, as at a Cornell box; otherwise [`Camera::overview`] from the south-west,
    /// above ([`DEFAULT_VIEW`]), which shows a closed room's inside.
    pub fn default_view(field: &SolutionField, up: DVec3) -> Self {
        let up = up.normalize();
        let turn = glam::DQuat::from_rotation_arc(DVec3::Z, up);
        let (x, y) = (turn * DVec3::X, turn * DVec3::Y);
        let points: Vec<DVec3> =
            field.scene.faces.iter().flat_map(|f| f.vertices.iter().copied()).collect();
        let extent = |axis: DVec3| {
            let (lo, hi) = points.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.dot(axis)), hi.max(p.dot(axis)))
            });
            (lo, hi)
        };
        let ((x0, x1), (y0, y1), (z0, z1)) = (extent(x), extent(y), extent(up));
        let centre = 0.5 * ((x0 + x1) * x + (y0 + y1) * y + (z0 + z1) * up);
        for (side, across, depth) in [
            (-y, x1 - x0, y1 - y0),
            (-x, y1 - y0, x1 - x0),
            (x, y1 - y0, x1 - x0),
            (y, x1 - x0, y1 - y0),
        ] {
            if side_is_open(field, side, across * (z1 - z0), depth) {
                // Far enough that the open side (1.3 times as wide as high fits the default
                // picture) fills the view, with a margin.
                let half = (0.5 * (z1 - z0)).max(0.5 * across / 1.3);
                let distance = 0.5 * depth + 1.1 * half / (0.5 * FOV_DEGREES.to_radians()).tan();
                return Self {
                    eye: centre + side * distance,
                    target: centre,
                    fov_degrees: FOV_DEGREES,
                    up,
                };
            }
        }
        Self::overview(field, turn * DEFAULT_VIEW, up)
    }
}

/// Whether the side of the scene's box toward `side` is open: the faces on it (within 1% of the
/// box's depth) that face inward cover less than half of its `area`.
fn side_is_open(field: &SolutionField, side: DVec3, area: f64, depth: f64) -> bool {
    let faces = &field.scene.faces;
    let far =
        faces.iter().flat_map(|f| f.vertices.iter()).map(|v| v.dot(side)).fold(f64::MIN, f64::max);
    let covered: f64 = faces
        .iter()
        .filter(|f| f.frame.normal.dot(side) < -0.5)
        .filter(|f| f.vertices.iter().all(|v| v.dot(side) >= far - 0.01 * depth))
        .map(|f| f.area())
        .sum();
    covered < 0.5 * area
}

/// The default direction of [`Camera::overview`] in a z-up scene: from the south-west, above.
pub const DEFAULT_VIEW: DVec3 = DVec3::new(-0.6, -1.0, 0.8);

crate::vocabulary::named_options! {
    /// How values become colours.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum Tone as "tone" {
        /// Proportional to the value, from the smallest to the largest (grey) or from 0 (colour)
        Linear = "linear",
        /// Proportional to the logarithm, over three decades below the largest value
        Log = "log",
        /// The linear scale to the power 1/2.2 (as a display's gamma): dark values spread out
        Gamma = "gamma",
    }
}

/// Decades below the largest value that [`Tone::Log`] shows.
const LOG_DECADES: f64 = 3.0;
/// The exponent of [`Tone::Gamma`].
const GAMMA: f64 = 2.2;

impl Tone {
    /// The range actually shown for values spanning `(lo, hi)`: a log scale starts three decades
    /// below `hi` (or at `lo` if higher), and shows nothing of values <= 0.
    fn span(self, (lo, hi): (f64, f64)) -> (f64, f64) {
        match self {
            Self::Log if hi > 0.0 => (lo.max(hi * 10f64.powf(-LOG_DECADES)), hi),
            _ => (lo, hi),
        }
    }

    /// Position in [0, 1] of `v` on the scale `span` (from [`Tone::span`]).
    fn position(self, v: f64, (lo, hi): (f64, f64)) -> f64 {
        let linear = ((v - lo) / (hi - lo)).clamp(0.0, 1.0);
        match self {
            Self::Linear => linear,
            Self::Gamma => linear.powf(1.0 / GAMMA),
            Self::Log if lo > 0.0 => ((v.max(lo) / lo).ln() / (hi / lo).ln()).clamp(0.0, 1.0),
            Self::Log => linear,
        }
    }

    /// The value at position `t` of the scale `span` (the inverse of [`Tone::position`]).
    fn value(self, t: f64, (lo, hi): (f64, f64)) -> f64 {
        match self {
            Self::Linear => lo + t * (hi - lo),
            Self::Gamma => lo + t.powf(GAMMA) * (hi - lo),
            Self::Log if lo > 0.0 => lo * (hi / lo).powf(t),
            Self::Log => lo + t * (hi - lo),
        }
    }
}

const BAR_WIDTH: u32 = 150;
const BACKGROUND: [u8; 3] = [255, 255, 255];

/// Renders `field` (u_n, or the flux that `quantity` names on the colour bar) seen by `camera`
/// into a `width` x `height` PNG at `path` titled `title`, through the tone map `tone`. The scale spans u_n over the elements of non-emitting faces (emitters, usually
/// far brighter, are clipped to the top colour) unless every face emits. With r, g and b bands the
/// picture is in colour, on one scale from 0 for the three bands (so that their ratios, the
/// colours, are kept); otherwise in viridis false colour.
pub fn render_png(
    field: &SolutionField,
    camera: &Camera,
    (width, height): (u32, u32),
    (title, quantity): (&str, &str),
    tone: Tone,
    path: &Path,
) -> Result<()> {
    if width < BAR_WIDTH + 100 || height < 100 || width > 8192 || height > 8192 {
        return Err(Error::InvalidParameter {
            name: "picture size",
            value: format!("{width}x{height}"),
            reason: format!("width in [{}, 8192], height in [100, 8192]", BAR_WIDTH + 100),
        });
    }
    let forward = (camera.target - camera.eye).normalize();
    if !forward.is_finite() {
        return Err(Error::InvalidParameter {
            name: "view",
            value: format!("{} -> {}", camera.eye, camera.target),
            reason: "the eye and the target must differ".into(),
        });
    }
    let rgb = rgb_bands(field);
    let span = tone.span(match &rgb {
        Some(bands) => (0.0, exposure(field, bands)),
        None => colour_range(field, &[field.u; 3]),
    });
    let mut image = vec![0u8; (width * height * 3) as usize];
    for px in image.chunks_mut(3) {
        px.copy_from_slice(&BACKGROUND);
    }
    let paint = |v: [f64; 3]| -> [u8; 3] {
        match rgb {
            Some(_) => v.map(|c| (255.0 * tone.position(c, span)).round() as u8),
            None => colour(tone.position(v[0], span)),
        }
    };
    let values: [&[f64]; 3] = rgb.unwrap_or([field.u; 3]);
    let picture = (width - BAR_WIDTH, height);
    rasterize(field, camera, forward, picture, width, &values, &paint, &mut image);
    register_font();
    {
        let root = BitMapBackend::with_buffer(&mut image, (width, height)).into_drawing_area();
        let bar = ColourBar { span, tone, colour: rgb.is_some(), quantity };
        draw_colour_bar(&root, (width, height), &bar, title)?;
        root.present().map_err(plot_error)?;
    }
    image::save_buffer(path, &image, width, height, image::ColorType::Rgb8)
        .map_err(|e| std::io::Error::other(format!("{}: {e}", path.display())))?;
    Ok(())
}

/// The r, g and b bands' nodal values, in that order, when all three were solved.
fn rgb_bands<'a>(field: &SolutionField<'a>) -> Option<[&'a [f64]; 3]> {
    let band = |c: usize| field.bands.iter().find(|b| b.channel == c).map(|b| b.u.as_slice());
    Some([band(0)?, band(1)?, band(2)?])
}

/// The span of the colour scale over the nodal values `bands` (see [`render_png`]).
fn colour_range(field: &SolutionField, bands: &[&[f64]; 3]) -> (f64, f64) {
    let elements = field.mesh.elements();
    let span = |emitters: bool| {
        (0..elements.len())
            .filter(|&j| emitters || field.scene.faces[elements[j].face].emission == 0.0)
            .flat_map(|j| bands.iter().flat_map(move |u| field.vertex_values_of(u, j)))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
    };
    let (lo, hi) = match span(false) {
        (lo, hi) if lo <= hi => (lo, hi),
        _ => span(true),
    };
    if hi > lo { (lo, hi) } else { (lo - 0.5, lo + 0.5) }
}

/// Share of the non-emitting elements that a colour picture shows below white (the rest, next to
/// the lights, are clipped as in a photograph): the largest value would leave the rest of a lit
/// room dark.
const EXPOSURE_QUANTILE: f64 = 0.95;

/// The top of a colour picture's scale: the [`EXPOSURE_QUANTILE`] of the brightest band over the
/// non-emitting elements (all elements if every one emits).
fn exposure(field: &SolutionField, bands: &[&[f64]; 3]) -> f64 {
    let elements = field.mesh.elements();
    let brightest = |j: usize| bands.iter().map(|u| field.element_mean(u, j)).fold(0.0, f64::max);
    let lit = |j: &usize| field.scene.faces[elements[*j].face].emission == 0.0;
    let mut values: Vec<f64> = (0..elements.len()).filter(lit).map(brightest).collect();
    if values.is_empty() {
        values = (0..elements.len()).map(brightest).collect();
    }
    values.sort_by(f64::total_cmp);
    let top = values[((values.len() - 1) as f64 * EXPOSURE_QUANTILE).round() as usize];
    if top > 0.0 { top } else { 1.0 }
}

/// Draws every element facing the camera into the picture area `(w, h)` of `image` (rows of
/// `stride` pixels), with a depth buffer and the three nodal `values` interpolated across the
/// element and turned into a pixel by `paint`.
#[allow(clippy::too_many_arguments)]
fn rasterize(
    field: &SolutionField,
    camera: &Camera,
    forward: DVec3,
    (w, h): (u32, u32),
    stride: u32,
    values: &[&[f64]; 3],
    paint: &dyn Fn([f64; 3]) -> [u8; 3],
    image: &mut [u8],
) {
    // Looking along the up direction: any direction across the view will do.
    let up_hint = if forward.cross(camera.up).length() > 1e-6 {
        camera.up
    } else {
        forward.any_orthonormal_vector()
    };
    let right = forward.cross(up_hint).normalize();
    let up = right.cross(forward);
    let focal = 0.5 * h as f64 / (0.5 * camera.fov_degrees.to_radians()).tan();
    let near = 1e-6 * (camera.target - camera.eye).length();
    // Screen position and depth (distance along the view direction).
    let project = |p: DVec3| -> (DVec2, f64) {
        let d = p - camera.eye;
        let depth = d.dot(forward);
        let s = DVec2::new(d.dot(right), d.dot(up)) * (focal / depth);
        (DVec2::new(0.5 * w as f64 + s.x, 0.5 * h as f64 - s.y), depth)
    };
    let mut depth_buffer = vec![f64::INFINITY; (w * h) as usize];
    for (j, e) in field.mesh.elements().iter().enumerate() {
        let normal = field.scene.faces[e.face].frame.normal;
        if normal.dot(camera.eye - e.centroid()) <= 0.0 {
            continue; // the back of a face: it neither radiates nor is drawn
        }
        let projected = e.vertices.map(project);
        if projected.iter().any(|(_, z)| *z <= near) {
            continue;
        }
        // at[k][m]: quantity m at vertex k.
        let per_quantity = values.map(|u| field.vertex_values_of(u, j));
        let at: [[f64; 3]; 3] = [0, 1, 2].map(|k| per_quantity.map(|q| q[k]));
        let [a, b, c] = projected.map(|(s, _)| s);
        let area = (b - a).perp_dot(c - a);
        if area.abs() < 1e-12 {
            continue;
        }
        let lo = a.min(b).min(c).max(DVec2::ZERO).floor();
        let hi = a.max(b).max(c).min(DVec2::new(w as f64 - 1.0, h as f64 - 1.0)).ceil();
        if lo.x > hi.x || lo.y > hi.y {
            continue; // off the picture
        }
        for y in lo.y as u32..=hi.y as u32 {
            for x in lo.x as u32..=hi.x as u32 {
                let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                let l = [(c - b).perp_dot(p - b), (a - c).perp_dot(p - c), (b - a).perp_dot(p - a)]
                    .map(|v| v / area);
                if l.iter().any(|&v| v < -1e-9) {
                    continue;
                }
                // Perspective-correct interpolation: 1/depth is affine on the screen.
                let inv = [0, 1, 2].map(|k| l[k] / projected[k].1);
                let inv_depth: f64 = inv.iter().sum();
                let depth = 1.0 / inv_depth;
                let k = (y * w + x) as usize;
                if depth >= depth_buffer[k] {
                    continue;
                }
                depth_buffer[k] = depth;
                let value =
                    [0, 1, 2].map(|q| (0..3).map(|m| inv[m] * at[m][q]).sum::<f64>() / inv_depth);
                let o = 3 * (y * stride + x) as usize;
                image[o..o + 3].copy_from_slice(&paint(value));
            }
        }
    }
}

/// The viridis colour map at t in [0, 1] (nine control points, linear in between).
fn colour(t: f64) -> [u8; 3] {
    const MAP: [[f64; 3]; 9] = [
        [68.0, 1.0, 84.0],
        [71.0, 44.0, 122.0],
        [59.0, 81.0, 139.0],
        [44.0, 113.0, 142.0],
        [33.0, 144.0, 141.0],
        [39.0, 173.0, 129.0],
        [92.0, 200.0, 99.0],
        [170.0, 220.0, 50.0],
        [253.0, 231.0, 37.0],
    ];
    let x = t * (MAP.len() - 1) as f64;
    let k = (x.floor() as usize).min(MAP.len() - 2);
    let f = x - k as f64;
    [0, 1, 2].map(|c| (MAP[k][c] * (1.0 - f) + MAP[k + 1][c] * f).round() as u8)
}

/// What the colour bar shows: the scale, its tone map, and whether the picture is in colour
/// (then the bar is a grey ramp: the level of each of r, g and b).
struct ColourBar<'a> {
    span: (f64, f64),
    tone: Tone,
    colour: bool,
    /// What the field is (`u`, or an absorbed flux).
    quantity: &'a str,
}

fn draw_colour_bar<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    (width, height): (u32, u32),
    bar: &ColourBar,
    title: &str,
) -> Result<()> {
    let x0 = (width - BAR_WIDTH + 20) as i32;
    let (top, bottom) = (40i32, height as i32 - 40);
    let steps = (bottom - top).max(1);
    for k in 0..steps {
        let t = 1.0 - k as f64 / steps as f64;
        let level = (255.0 * t).round() as u8;
        let [r, g, b] = if bar.colour { [level; 3] } else { colour(t) };
        root.draw(&Rectangle::new(
            [(x0, top + k), (x0 + 24, top + k + 1)],
            RGBColor(r, g, b).filled(),
        ))
        .map_err(plot_error)?;
    }
    root.draw(&Rectangle::new([(x0, top), (x0 + 24, bottom)], BLACK.stroke_width(1)))
        .map_err(plot_error)?;
    let font = ("sans-serif", 14).into_font();
    for k in 0..=4 {
        let t = k as f64 / 4.0;
        let y = bottom - (t * (bottom - top) as f64).round() as i32;
        let value = bar.tone.value(t, bar.span);
        root.draw(&PathElement::new([(x0 + 24, y), (x0 + 30, y)], BLACK)).map_err(plot_error)?;
        root.draw(&Text::new(format!("{value:.3e}"), (x0 + 33, y - 7), font.clone()))
            .map_err(plot_error)?;
    }
    let what =
        if bar.colour { format!("{} of r, g, b", bar.quantity) } else { bar.quantity.to_string() };
    let scale = match bar.tone {
        Tone::Gamma => format!("gamma {GAMMA}"),
        tone => format!("{} scale", tone.name()),
    };
    for (k, line) in [what, scale].into_iter().enumerate() {
        let y = top - 36 + 16 * k as i32;
        root.draw(&Text::new(line, (x0 - 12, y), font.clone())).map_err(plot_error)?;
    }
    root.draw(&Text::new(title.to_string(), (10, 10), ("sans-serif", 16).into_font()))
        .map_err(plot_error)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elements_partly_or_wholly_off_the_picture_are_clipped() {
        // Found by hand: an eye inside the room put elements beyond the right edge.
        let scene = crate::scene::cube().unwrap();
        let mesh = crate::mesh::Mesh::new(&scene, &crate::mesh::MeshKind::Uniform, 2).unwrap();
        let disc = crate::discretization::Discretization::new(
            &scene,
            &mesh,
            crate::discretization::Method::Centroid,
        )
        .unwrap();
        let u: Vec<f64> = (0..disc.dof()).map(|k| k as f64).collect();
        let field = SolutionField {
            scene: &scene,
            mesh: &mesh,
            disc: &disc,
            u: &u,
            emission: &u,
            bands: &[],
            cases: &[],
        };
        let dir = std::env::temp_dir().join(format!("radiosity-render-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for eye in
            [DVec3::new(0.9, 0.8, 0.5), DVec3::new(0.5, 0.5, 0.5), DVec3::new(-3.0, 0.5, 0.5)]
        {
            let target = DVec3::new(0.1, 0.2, 0.4);
            let camera = Camera { eye, target, fov_degrees: 60.0, up: DVec3::Z };
            render_png(
                &field,
                &camera,
                (400, 300),
                ("t", "u"),
                Tone::Linear,
                &dir.join("cube.png"),
            )
            .unwrap();
        }
    }

    #[test]
    fn the_colour_map_runs_from_dark_violet_to_yellow() {
        assert_eq!(colour(0.0), [68, 1, 84]);
        assert_eq!(colour(1.0), [253, 231, 37]);
        assert_eq!(colour(0.5), [33, 144, 141]);
    }

    #[test]
    fn the_default_camera_looks_through_an_open_side_or_over_a_closed_room() {
        let field_of = |scene: &crate::scene::Scene, f: &mut dyn FnMut(&SolutionField)| {
            let mesh = crate::mesh::Mesh::new(scene, &crate::mesh::MeshKind::Uniform, 0).unwrap();
            let method = crate::discretization::Method::Centroid;
            let disc = crate::discretization::Discretization::new(scene, &mesh, method).unwrap();
            let u = vec![0.0; disc.dof()];
            f(&SolutionField {
                scene,
                mesh: &mesh,
                disc: &disc,
                u: &u,
                emission: &u,
                bands: &[],
                cases: &[],
            });
        };
        // The Cornell box (y up, open toward +z and -z): level, from +z, toward the viewer in
        // the y-up convention.
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/cornell-box/CornellBox-Original.obj");
        let cornell = crate::scene::load(&path).unwrap();
        field_of(&cornell, &mut |field| {
            let c = Camera::default_view(field, DVec3::Y * 2.0);
            let view = c.eye - c.target;
            assert!(view.z > 3.0 && view.x.abs() < 1e-12 && view.y.abs() < 1e-12, "{view}");
            assert_eq!(c.up, DVec3::Y);
        });
        // A closed cube, z up: the overview from the south-west, above.
        let cube = crate::scene::cube().unwrap();
        field_of(&cube, &mut |field| {
            let c = Camera::default_view(field, DVec3::Z);
            assert_eq!(c, Camera::overview(field, DEFAULT_VIEW, DVec3::Z));
        });
    }
}
