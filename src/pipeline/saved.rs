//! Operators saved and loaded: a run's K (dense or compressed) written once and reused by later
//! runs of the same problem (many solves, another day's emission).
//!
//! The file: the magic line `radiosity operator\n`, a format version, a JSON header that says
//! what the operator was built for (scene, geometry hash, mesh, method, integrals, size), the
//! operator in little-endian binary, and a checksum of all before it. A file built for another
//! problem is refused, naming what differs; a truncated, damaged or foreign file is refused,
//! saying so.

use std::fs::File;
use std::io::{BufReader, BufWriter};
use std::path::Path;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::device::blocks_on_device;
use super::{BuiltOperator, Problem, RunConfig, TimedAssembly};
use crate::assembly::{Assembly, CollocationMatrix, check_fits};
use crate::error::{Error, Result};
use crate::operator::{BinaryReader, BinaryWriter, CompressedOperator, OperatorChoice};
use crate::vocabulary::Named;

/// The first bytes of every operator file.
const MAGIC: &[u8] = b"radiosity operator\n";

/// The layout's version: files of another are refused (2: block values carry their precision).
const VERSION: u64 = 2;

/// What an operator was built for: everything that decides its entries.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OperatorHeader {
    /// `dense` or `compressed`.
    pub operator: String,
    /// The scene's name.
    pub surface: String,
    /// FNV-1a hash of the faces (vertices, rho, sides), the elements and the nodes.
    pub geometry_hash: String,
    /// Mesh kind and refinement levels.
    pub mesh: String,
    /// Refinement levels.
    pub refine: u32,
    /// Collocation method (and α).
    pub method: String,
    /// The collocation integrals (quadrature and its parameters, IMT nodes, far field).
    pub integrals: serde_json::Value,
    /// Elements.
    pub n: usize,
    /// Unknowns.
    pub dof: usize,
    /// Relative tolerance of the low-rank blocks (compressed).
    pub compression_tolerance: Option<f64>,
}

impl OperatorHeader {
    /// The header of the operator (dense or compressed) that `config` builds for `problem`.
    fn of(config: &RunConfig, problem: &Problem, operator: OperatorChoice) -> Self {
        let method = match config.method.alpha() {
            Some(alpha) => format!("{} (alpha {alpha})", config.method.name()),
            None => config.method.name().to_string(),
        };
        let a = &config.assembly;
        Self {
            operator: operator.name().to_string(),
            surface: problem.scene.name.clone(),
            geometry_hash: format!("{:016x}", geometry_hash(problem)),
            mesh: config.mesh.name().to_string(),
            refine: config.refine,
            method,
            integrals: serde_json::json!({
                "quadrature": a.quadrature,
                "imt_nodes": a.imt_nodes,
                "far_field": a.far_field,
            }),
            n: problem.mesh.len(),
            dof: problem.disc.dof(),
            compression_tolerance: (operator == OperatorChoice::Compressed)
                .then_some(config.compression.tolerance),
        }
    }

    /// What differs between the header a file holds and this run's (`None`: the same problem).
    fn differences(&self, run: &Self) -> Option<String> {
        let mut differ = Vec::new();
        let mut compare = |what: &str, saved: String, here: String| {
            if saved != here {
                differ.push(format!("{what} {saved} (this run: {here})"));
            }
        };
        compare("scene", self.surface.clone(), run.surface.clone());
        compare("mesh", format!("{} refine {}", self.mesh, self.refine), {
            format!("{} refine {}", run.mesh, run.refine)
        });
        compare("method", self.method.clone(), run.method.clone());
        compare("integrals", self.integrals.to_string(), run.integrals.to_string());
        compare("size", format!("n = {}, dof = {}", self.n, self.dof), {
            format!("n = {}, dof = {}", run.n, run.dof)
        });
        let tolerance = |t: Option<f64>| t.map_or("none".into(), |t| format!("{t:e}"));
        compare(
            "compression tolerance",
            tolerance(self.compression_tolerance),
            tolerance(run.compression_tolerance),
        );
        if differ.is_empty() && self.geometry_hash != run.geometry_hash {
            differ.push("geometry (faces, rho or elements moved; hash differs)".into());
        }
        (!differ.is_empty()).then(|| differ.join("; "))
    }
}

/// FNV-1a over the bits of what decides K besides the method and the integrals: every face's
/// vertices, reflectivity and side, every element's vertices, every node's position and rho.
fn geometry_hash(problem: &Problem) -> u64 {
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    let mut add = |bits: u64| {
        for byte in bits.to_le_bytes() {
            hash = (hash ^ byte as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    let Problem { scene, mesh, disc, .. } = problem;
    for v in [scene.origin.x, scene.origin.y, scene.origin.z] {
        add(v.to_bits());
    }
    for face in &scene.faces {
        add(face.vertices.len() as u64);
        face.vertices.iter().flat_map(|v| v.to_array()).for_each(|x| add(x.to_bits()));
        add(face.rho.to_bits());
        add(face.frame.normal.x.to_bits());
    }
    for element in mesh.elements() {
        add(element.face as u64);
        element.vertices.iter().flat_map(|v| v.to_array()).for_each(|x| add(x.to_bits()));
    }
    for node in disc.nodes() {
        node.position.to_array().iter().for_each(|x| add(x.to_bits()));
        add(node.rho.to_bits());
    }
    hash
}

/// Writes `operator`, built by `config` for `problem`, to `path`.
pub fn save_operator(
    path: &Path,
    operator: &BuiltOperator,
    config: &RunConfig,
    problem: &Problem,
) -> Result<()> {
    let kind = match operator {
        BuiltOperator::Dense(_) => OperatorChoice::Dense,
        BuiltOperator::Compressed { .. } => OperatorChoice::Compressed,
        BuiltOperator::Device { .. } => {
            return Err(Error::InvalidParameter {
                name: "save",
                value: path.display().to_string(),
                reason: "this matrix is in the GPU's memory; build it for the host (the CPU, or \
                         without the iterative solver) to save it"
                    .into(),
            });
        }
    };
    let header = OperatorHeader::of(config, problem, kind);
    let mut out = BinaryWriter::new(BufWriter::new(File::create(path)?));
    out.raw(MAGIC)?;
    out.u64(VERSION)?;
    out.bytes(&serde_json::to_vec(&header).expect("the header is JSON"))?;
    match operator {
        BuiltOperator::Dense(t) => out.f64s(t.assembled.matrix.as_slice())?,
        BuiltOperator::Compressed { op, .. } => op.write(&mut out)?,
        BuiltOperator::Device { .. } => unreachable!("refused above"),
    }
    out.finish()?;
    Ok(())
}

/// Reads the operator at `path` for `problem`, refusing one built for another problem than
/// `config` describes; its setup time is the time to read it.
pub fn load_operator(path: &Path, config: &RunConfig, problem: &Problem) -> Result<BuiltOperator> {
    let started = Instant::now();
    let name = path.display().to_string();
    let file = File::open(path)
        .map_err(|e| Error::DataFile { path: name.clone(), reason: e.to_string() })?;
    let len = file.metadata()?.len();
    let mut input = BinaryReader::new(BufReader::with_capacity(1 << 20, file), len, &name);
    if input.raw(MAGIC.len() as u64, "the magic line").ok().as_deref() != Some(MAGIC) {
        return Err(input
            .error("not an operator file of radiosity (write one with `assemble --save`)".into()));
    }
    let version = input.u64("the version")?;
    if version != VERSION {
        return Err(input.error(format!(
            "an operator file of format version {version}; this build reads version {VERSION}: \
             save it again"
        )));
    }
    let header: OperatorHeader = serde_json::from_slice(&input.bytes("the header")?)
        .map_err(|e| input.error(format!("damaged header: {e}")))?;
    let held = match OperatorChoice::parse(&header.operator) {
        Ok(kind @ (OperatorChoice::Dense | OperatorChoice::Compressed)) => kind,
        _ => return Err(input.error(format!("damaged header: operator '{}'", header.operator))),
    };
    let asked = match config.operator {
        OperatorChoice::Auto => held,
        kind => kind,
    };
    if asked != held {
        return Err(input.error(format!(
            "holds the {} operator, this run asks for the {} one",
            held.name(),
            asked.name()
        )));
    }
    // The header this run would write for the kind the file holds.
    let run = OperatorHeader::of(config, problem, held);
    if let Some(differ) = header.differences(&run) {
        return Err(input.error(format!("saved for another problem: {differ}")));
    }
    let dof = problem.disc.dof();
    let built = match held {
        OperatorChoice::Dense => {
            check_fits(8.0 * (dof as f64) * (dof as f64), dof)?;
            let values = input.f64s("the matrix")?;
            if values.len() != dof * dof {
                return Err(input.error(format!("damaged: {} entries for dof {dof}", values.len())));
            }
            let matrix = CollocationMatrix::from_rows(dof, values);
            let setup_seconds = started.elapsed().as_secs_f64();
            let assembled = Assembly { matrix, stats: Default::default() };
            BuiltOperator::Dense(TimedAssembly::loaded(assembled, setup_seconds))
        }
        OperatorChoice::Auto => unreachable!("a file holds a dense or a compressed operator"),
        OperatorChoice::Compressed => {
            let op = CompressedOperator::read(&mut input)?;
            if op.dof() != dof {
                return Err(input.error(format!("damaged: {} unknowns for dof {dof}", op.dof())));
            }
            let setup_seconds = started.elapsed().as_secs_f64();
            let on_device = blocks_on_device(config, &op);
            BuiltOperator::Compressed {
                op: Box::new(op),
                on_device,
                build_traffic: None,
                setup_seconds,
                preparation_seconds: 0.0,
            }
        }
    };
    input.finish()?;
    Ok(built)
}
