//! The uniform tables the collocation kernels read: the IMT rule and the far-field rules.

use super::layout;
use super::shaders::Precision;
use crate::assembly::AssemblyOptions;
use crate::discretization::Method;
use crate::error::{Error, Result};
use crate::kernels::far_field::FarFieldRule;
use crate::quadrature::ImtRule;

/// Where the rules array's parts start and how long they are.
#[derive(Clone, Copy)]
pub(super) struct RuleCounts {
    pub(super) imt: usize,
    pub(super) rule_offset: usize,
    pub(super) bands: usize,
}

/// The far-field rule the kernels use: in f64 the CPU's for the method (when enabled); in f32 the
/// single-precision one for both methods, where the closed forms' cancellation far from the node
/// would cost most of f32's digits.
pub(super) fn far_field_rule(
    precision: Precision,
    method: Method,
    enabled: bool,
) -> Option<FarFieldRule> {
    match precision {
        Precision::F32 => Some(FarFieldRule::single_precision()),
        Precision::F64 => enabled.then(|| FarFieldRule::for_weights(method.nodes_per_element())),
    }
}

/// The uniform tables (TABLE_SIZE entries of 4 reals): IMT nodes (x, w), then one header per
/// far-field band ((ratio + 1)², first entry, count) and the bands' points (u, v, w).
pub(super) fn tables(
    options: &AssemblyOptions,
    method: Method,
    precision: Precision,
) -> Result<(Vec<f64>, RuleCounts)> {
    let imt = ImtRule::new(options.imt_nodes.max(2));
    let mut entries: Vec<[f64; 4]> =
        imt.nodes().iter().zip(imt.weights()).map(|(&x, &w)| [x, w, 0.0, 0.0]).collect();
    let rule_offset = entries.len();
    let mut bands = 0;
    if let Some(rule) = far_field_rule(precision, method, options.far_field) {
        bands = rule.bands.len();
        let mut first = rule_offset + bands;
        for band in &rule.bands {
            entries.push([
                (band.ratio + 1.0).powi(2),
                first as f64,
                band.rule.points().len() as f64,
                0.0,
            ]);
            first += band.rule.points().len();
        }
        for band in &rule.bands {
            entries.extend(band.rule.points().iter().map(|&[u, v, w]| [u, v, w, 0.0]));
        }
    }
    if entries.len() > layout::TABLE_SIZE {
        return Err(Error::InvalidParameter {
            name: "imt-nodes",
            value: options.imt_nodes.to_string(),
            reason: format!(
                "the GPU kernels' tables hold {} entries and the far-field rules take {}",
                layout::TABLE_SIZE,
                entries.len() - imt.nodes().len()
            ),
        });
    }
    entries.resize(layout::TABLE_SIZE, [0.0; 4]);
    Ok((
        entries.into_iter().flatten().collect(),
        RuleCounts { imt: imt.nodes().len(), rule_offset, bands },
    ))
}
