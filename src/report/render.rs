//! A false-colour picture of a solution, rendered headlessly by a small software rasterizer
//! (perspective camera, depth buffer, back faces culled so that a closed room seen from outside
//! shows its inside), with a colour bar drawn by plotters and encoded as PNG.

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
}

impl Camera {
    /// A view of the whole scene from `direction` (from the scene's centre toward the eye),
    /// far enough that its bounding sphere fits the picture.
    pub fn overview(field: &SolutionField, direction: DVec3) -> Self {
        let (lo, hi) = field.scene.faces.iter().map(|f| f.bounding_box()).fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), (a, b)| (lo.min(a), hi.max(b)),
        );
        let centre = 0.5 * (lo + hi);
        let radius = 0.5 * (hi - lo).length();
        let fov_degrees: f64 = 40.0;
        let distance = radius / (0.5 * fov_degrees.to_radians()).sin();
        Self { eye: centre + direction.normalize() * distance, target: centre, fov_degrees }
    }
}

/// The default direction of [`Camera::overview`]: from the south-west, above.
pub const DEFAULT_VIEW: DVec3 = DVec3::new(-0.6, -1.0, 0.8);

const BAR_WIDTH: u32 = 150;
const BACKGROUND: [u8; 3] = [255, 255, 255];

/// Renders `field` (u_n) seen by `camera` into a `width` x `height` PNG at `path`. The colour
/// scale spans u_n over the elements of non-emitting faces (emitters, usually far brighter, are
/// clipped to the top colour) unless every face emits.
pub fn render_png(
    field: &SolutionField,
    camera: &Camera,
    (width, height): (u32, u32),
    title: &str,
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
    let range = colour_range(field);
    let mut image = vec![0u8; (width * height * 3) as usize];
    for px in image.chunks_mut(3) {
        px.copy_from_slice(&BACKGROUND);
    }
    rasterize(field, camera, forward, (width - BAR_WIDTH, height), width, range, &mut image);
    register_font();
    {
        let root = BitMapBackend::with_buffer(&mut image, (width, height)).into_drawing_area();
        draw_colour_bar(&root, (width, height), range, title)?;
        root.present().map_err(plot_error)?;
    }
    image::save_buffer(path, &image, width, height, image::ColorType::Rgb8)
        .map_err(|e| std::io::Error::other(format!("{}: {e}", path.display())))?;
    Ok(())
}

/// The span of the colour scale (see [`render_png`]).
fn colour_range(field: &SolutionField) -> (f64, f64) {
    let elements = field.mesh.elements();
    let span = |emitters: bool| {
        (0..elements.len())
            .filter(|&j| emitters || field.scene.faces[elements[j].face].emission == 0.0)
            .flat_map(|j| field.vertex_values(j))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
    };
    let (lo, hi) = match span(false) {
        (lo, hi) if lo <= hi => (lo, hi),
        _ => span(true),
    };
    if hi > lo { (lo, hi) } else { (lo - 0.5, lo + 0.5) }
}

/// Draws every element facing the camera into the picture area `(w, h)` of `image` (rows of
/// `stride` pixels), with a depth buffer and u_n interpolated across the element.
fn rasterize(
    field: &SolutionField,
    camera: &Camera,
    forward: DVec3,
    (w, h): (u32, u32),
    stride: u32,
    range: (f64, f64),
    image: &mut [u8],
) {
    let up_hint = if forward.cross(DVec3::Z).length() > 1e-6 { DVec3::Z } else { DVec3::Y };
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
        let values = field.vertex_values(j);
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
                let value = (0..3).map(|m| inv[m] * values[m]).sum::<f64>() / inv_depth;
                let t = ((value - range.0) / (range.1 - range.0)).clamp(0.0, 1.0);
                let o = 3 * (y * stride + x) as usize;
                image[o..o + 3].copy_from_slice(&colour(t));
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

fn draw_colour_bar<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    (width, height): (u32, u32),
    (lo, hi): (f64, f64),
    title: &str,
) -> Result<()> {
    let x0 = (width - BAR_WIDTH + 20) as i32;
    let (top, bottom) = (40i32, height as i32 - 40);
    let steps = (bottom - top).max(1);
    for k in 0..steps {
        let t = 1.0 - k as f64 / steps as f64;
        let [r, g, b] = colour(t);
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
        let value = lo + t * (hi - lo);
        root.draw(&PathElement::new([(x0 + 24, y), (x0 + 30, y)], BLACK)).map_err(plot_error)?;
        root.draw(&Text::new(format!("{value:.3e}"), (x0 + 33, y - 7), font.clone()))
            .map_err(plot_error)?;
    }
    root.draw(&Text::new("u".to_string(), (x0 + 8, top - 25), font.clone())).map_err(plot_error)?;
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
        let field = SolutionField { scene: &scene, mesh: &mesh, disc: &disc, u: &u, emission: &u };
        let dir = std::env::temp_dir().join(format!("radiosity-render-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for eye in
            [DVec3::new(0.9, 0.8, 0.5), DVec3::new(0.5, 0.5, 0.5), DVec3::new(-3.0, 0.5, 0.5)]
        {
            let camera = Camera { eye, target: DVec3::new(0.1, 0.2, 0.4), fov_degrees: 60.0 };
            render_png(&field, &camera, (400, 300), "t", &dir.join("cube.png")).unwrap();
        }
    }

    #[test]
    fn the_colour_map_runs_from_dark_violet_to_yellow() {
        assert_eq!(colour(0.0), [68, 1, 84]);
        assert_eq!(colour(1.0), [253, 231, 37]);
        assert_eq!(colour(0.5), [33, 144, 141]);
    }
}
