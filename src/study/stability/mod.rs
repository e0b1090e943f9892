//! Numerical stability at the edges: extreme node–element geometry for the kernels on every
//! backend ([`extreme`], `study stability`), and stiff systems as rho → 1 ([`stiff`], `study stiff`).

pub mod extreme;
pub mod stiff;

use serde::Serialize;

use crate::error::Result;
use crate::gpu::Precision;
use crate::pipeline::{self, Backend};

/// The study ids this module answers.
pub const STUDY_IDS: [&str; 2] = ["stability", "stiff"];

/// Rows of `study stability`, with the backends left out and why.
#[derive(Clone, Debug, Serialize)]
pub struct StabilityResult {
    /// Study id.
    pub study: &'static str,
    /// One row per case, method and backend.
    pub rows: Vec<extreme::ExtremeRow>,
    /// Rows over their bound.
    pub failed: usize,
    /// Notes (backends left out).
    pub notes: Vec<String>,
}

/// Rows of `study stiff`.
#[derive(Clone, Debug, Serialize)]
pub struct StiffResult {
    /// Study id.
    pub study: &'static str,
    /// One row per scene and rho.
    pub rows: Vec<stiff::StiffRow>,
    /// Notes.
    pub notes: Vec<String>,
}

/// The backends of the stability study: the CPU, and the GPU in f64 and f32 (asked for: the
/// adapter required; `None`: where one is found).
fn backends(asked: Option<Backend>, notes: &mut Vec<String>) -> Result<Vec<Backend>> {
    const PRECISIONS: [Precision; 2] = [Precision::F64, Precision::F32];
    Ok(match asked {
        Some(Backend::Cpu) => vec![Backend::Cpu],
        Some(Backend::Gpu(_)) => {
            let gpus = PRECISIONS.map(|p| Backend::Gpu(p).found());
            std::iter::once(Ok(Backend::Cpu)).chain(gpus).collect::<Result<_>>()?
        }
        None => pipeline::cpu_and_found_gpus(&PRECISIONS, notes),
    })
}

/// `study stability`.
pub fn run_stability(asked: Option<Backend>) -> Result<StabilityResult> {
    let mut notes = vec![
        "relative_error: max over the row's entries |K - reference| / max |reference| (absolute \
         where the reference is 0); reference: adaptive quadrature to 1e-15, in polar \
         coordinates about the node's foot near the element, of the plain integrand elsewhere; \
         closed forms: the CPU with the paper's closed forms for every pair (far-field rules off); \
         bound: 512 ulps times h / (the node's distance to the nearest edge or tangent-plane \
         trace)"
            .to_string(),
    ];
    let backends = backends(asked, &mut notes)?;
    let rows = extreme::run(&backends)?;
    let failed = rows.iter().filter(|r| !r.passed).count();
    Ok(StabilityResult { study: "stability", rows, failed, notes })
}

/// `study stiff` (assembly on the CPU, or on the GPU when asked).
pub fn run_stiff(asked: Option<Backend>) -> Result<StiffResult> {
    let backend = asked.unwrap_or(Backend::Cpu);
    let notes = vec![
        "u* = 1 + x/2 + y/4 + z/8 at the nodes, E = (I - K) u* with compensated dot products; \
         error_lu: plain LU; error_refined: the solver (condition estimate, refinement with \
         compensated residuals, singular systems refused); GMRES: the iterative solver at its \
         default tolerance (relative residual 1e-13), vs LU its difference from the refined LU \
         solution, its: its matrix-vector products; 'black top': the top face has rho = 0 (a \
         lamp), its rows taken out as u = E"
            .to_string(),
    ];
    Ok(StiffResult { study: "stiff", rows: stiff::run(backend)?, notes })
}
