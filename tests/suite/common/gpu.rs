//! What the GPU tests share: the adapter (or a failure that says how to get one), a scene of
//! thin elements, and the entry-by-entry comparison of two matrices.

use radiosity::assembly::CollocationMatrix;
use radiosity::gpu::{self, GpuContext, INSTALL_HINT};

/// The shared GPU context; none where RADIOSITY_GPU=skip. Without an adapter the test fails,
/// saying how to install one.
pub fn gpu() -> Option<&'static GpuContext> {
    if std::env::var("RADIOSITY_GPU").as_deref() == Ok("skip") {
        eprintln!("RADIOSITY_GPU=skip: GPU test skipped");
        return None;
    }
    match gpu::shared_context() {
        Ok(ctx) => Some(ctx),
        Err(e) => panic!("no usable GPU adapter: {e}\nGPU tests need one: {INSTALL_HINT}"),
    }
}

/// Largest difference between two matrices relative to the largest entry of each row.
pub fn max_row_relative_diff(a: &CollocationMatrix, b: &CollocationMatrix) -> (f64, usize, usize) {
    let mut worst = (0.0, 0, 0);
    for i in 0..a.dof() {
        let scale = a.row(i).iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
        for (j, (x, y)) in a.row(i).iter().zip(b.row(i)).enumerate() {
            let d = (x - y).abs() / scale;
            if d > worst.0 {
                worst = (d, i, j);
            }
        }
    }
    worst
}

/// A scene file (in a temporary folder named after `test`) of a lit floor under a shelf 0.01
/// wide and 1 long: its elements are thin, where the closed forms cancel.
pub fn sliver_scene(test: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("radiosity-gpu-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("sliver.toml");
    std::fs::write(
        &scene,
        "name = \"sliver-shelf\"\n[defaults]\nrho = 0.5\n\
         [[faces]]\nname = \"floor\"\nvertices = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]\n\
         emission = 1.0\n\
         [[faces]]\nname = \"shelf\"\n\
         vertices = [[0, 0.5, 0.3], [0, 0.51, 0.3], [1, 0.51, 0.3], [1, 0.5, 0.3]]\n",
    )
    .unwrap();
    scene
}
