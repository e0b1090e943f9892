//! The WGSL sources and how they are joined: `alias real = f64|f32;`, then the math library of that
//! precision, then the kernel. This is the only place shader text is assembled.

pub use crate::vocabulary::Precision;

const MATH_F64: &str = include_str!("../../shaders/math_f64.wgsl");
const MATH_F32: &str = include_str!("../../shaders/math_f32.wgsl");
const COLLOCATION: &str = include_str!("../../shaders/collocation.wgsl");
const CLIP: &str = include_str!("../../shaders/clip.wgsl");
const MATH_TEST: &str = include_str!("../../shaders/math_test.wgsl");
const MATVEC: &str = include_str!("../../shaders/matvec.wgsl");
const BLOCKS: &str = include_str!("../../shaders/blocks.wgsl");
const NARROW: &str = include_str!("../../shaders/narrow.wgsl");

fn with_math(precision: Precision, body: &str) -> String {
    let (alias, math) = match precision {
        Precision::F64 => ("alias real = f64;\n", MATH_F64),
        Precision::F32 => ("alias real = f32;\n", MATH_F32),
    };
    format!("{alias}{math}\n{body}")
}

/// The collocation kernels (entry points `assemble_full`, `assemble_pieces`, and
/// `assemble_cuts`, which clips elements on the device: shaders/clip.wgsl) for elements with
/// `per_element` basis functions (1 or 3); `far_field` keeps the far-field rule's code. Both are
/// written into the source rather than passed as pipeline-overridable constants: with wgpu 30 an
/// `override` set at pipeline creation left the linear kernel computing wrong values on lavapipe.
pub fn collocation(precision: Precision, per_element: u32, far_field: bool) -> String {
    with_math(
        precision,
        &format!(
            "const PER_ELEMENT: u32 = {per_element}u;\nconst FAR_FIELD: bool = {far_field};\n{COLLOCATION}\n{CLIP}"
        ),
    )
}

/// The product of a device-resident matrix stored in `precision` with vectors in f64 (entry
/// point `matvec`).
pub fn matvec(precision: Precision) -> String {
    let alias = match precision {
        Precision::F64 => "alias real = f64;\n",
        Precision::F32 => "alias real = f32;\n",
    };
    format!("{alias}{MATVEC}")
}

/// The product of the compressed operator's packed blocks, in f64 (entry points `low_rank_t`,
/// `block_rows`, `row_sums`).
pub fn blocks() -> String {
    BLOCKS.to_string()
}

/// f64 tiles of K narrowed to f32 storage, with each row's norms (entry point `narrow_rows`).
pub fn narrow() -> String {
    NARROW.to_string()
}

/// The math-library test kernel (entry point `math_eval`).
pub fn math_test(precision: Precision) -> String {
    with_math(precision, MATH_TEST)
}

/// Parses and validates a WGSL module with naga (f64 allowed), returning the module.
pub fn validate(source: &str) -> Result<naga::Module, String> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| e.emit_to_string(source))?;
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::FLOAT64,
    )
    .validate(&module)
    .map_err(|e| e.emit_to_string(source))?;
    Ok(module)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shader_parses_and_validates_in_both_precisions() {
        for p in [Precision::F64, Precision::F32] {
            let sources = [
                ("collocation, centroid", collocation(p, 1, false)),
                ("collocation, centroid, far field", collocation(p, 1, true)),
                ("collocation, linear", collocation(p, 3, true)),
                ("math_test", math_test(p)),
                ("matvec", matvec(p)),
                ("blocks", blocks()),
            ];
            for (name, src) in sources {
                if let Err(e) = validate(&src) {
                    panic!("{name} ({p:?}) does not validate:\n{e}");
                }
            }
        }
    }

    /// The WGSL constant `name` of type u32.
    fn wgsl_u32_constant(module: &naga::Module, name: &str) -> u32 {
        let (_, c) = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("no constant {name}"));
        match module.global_expressions[c.init] {
            naga::Expression::Literal(naga::Literal::U32(v)) => v,
            ref other => panic!("{name} is not a u32 literal: {other:?}"),
        }
    }

    #[test]
    fn layout_constants_match_the_host() {
        use super::super::layout;
        let module = validate(&collocation(Precision::F64, 3, true)).unwrap();
        assert_eq!(wgsl_u32_constant(&module, "VIEW_STRIDE") as usize, layout::VIEW_STRIDE);
        assert_eq!(wgsl_u32_constant(&module, "ELEMENT_STRIDE") as usize, layout::ELEMENT_STRIDE);
        assert_eq!(wgsl_u32_constant(&module, "WORKGROUP"), layout::WORKGROUP);
        assert_eq!(wgsl_u32_constant(&module, "TABLE_SIZE") as usize, layout::TABLE_SIZE);
        assert_eq!(wgsl_u32_constant(&module, "PER_ELEMENT"), 3);
        assert_eq!(wgsl_u32_constant(&module, "MAX_PIECES"), layout::MAX_PIECES);
        assert_eq!(wgsl_u32_constant(&module, "CUT_VIEW_HEADER") as usize, layout::CUT_VIEW_HEADER);
        assert_eq!(wgsl_u32_constant(&module, "SHADOW_HEADER") as usize, layout::SHADOW_HEADER);
        assert_eq!(wgsl_u32_constant(&module, "BOX_NODE_STRIDE") as usize, layout::BOX_NODE_STRIDE);
        let leaf = crate::visibility::ElementBoxes::LEAF;
        assert_eq!(wgsl_u32_constant(&module, "BOX_LEAF") as usize, leaf);
        // The IMT panels of the log moment, as on the CPU.
        let (_, c) = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some("LOG_PANEL_WIDTH"))
            .expect("LOG_PANEL_WIDTH");
        match module.global_expressions[c.init] {
            naga::Expression::Literal(naga::Literal::F64(v)) => {
                assert_eq!(v, crate::kernels::LOG_PANEL_WIDTH)
            }
            ref other => panic!("LOG_PANEL_WIDTH is not an f64 literal: {other:?}"),
        }
        // The clipping kernel's tolerances, and the near list's header, as on the host.
        let f64_constant = |name: &str| {
            let (_, c) =
                module.constants.iter().find(|(_, c)| c.name.as_deref() == Some(name)).expect(name);
            match module.global_expressions[c.init] {
                naga::Expression::Literal(naga::Literal::F64(v)) => v,
                ref other => panic!("{name} is not an f64 literal: {other:?}"),
            }
        };
        assert_eq!(f64_constant("ON_LINE"), crate::geometry::ON_LINE);
        assert_eq!(f64_constant("PLANE_TOLERANCE"), crate::visibility::PLANE_TOLERANCE);
        let (_, near) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some("NearList"))
            .expect("struct NearList");
        let naga::TypeInner::Struct { members, .. } = &near.inner else { panic!("NearList") };
        let offset = |name: &str| {
            members.iter().find(|m| m.name.as_deref() == Some(name)).expect(name).offset as u64
        };
        assert_eq!(offset("dispatch_x"), layout::NEAR_DISPATCH_OFFSET);
        assert_eq!(offset("hidden"), 4 * layout::CUT_TALLY_INDEX as u64);
        assert_eq!(offset("deep_dispatch_x"), layout::DEEP_DISPATCH_OFFSET);
        assert_eq!(offset("pairs"), layout::NEAR_HEADER_BYTES);
        let (_, params) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some("Params"))
            .expect("struct Params");
        assert_eq!(
            params.inner.size(module.to_ctx()) as usize,
            std::mem::size_of::<layout::Params>()
        );
    }

    #[test]
    fn f64_literals_keep_every_bit() {
        // naga must not round `lf` literals through f32: check the splits of pi and ln 2 and other
        // constants against the host's values.
        let module = validate(&math_test(Precision::F64)).unwrap();
        let want: &[(&str, f64)] = &[
            ("M_PIO2_HI", std::f64::consts::FRAC_PI_2),
            ("M_PI_HI", std::f64::consts::PI),
            ("M_INV_LN2", std::f64::consts::LOG2_E),
            ("M_SQRT2", std::f64::consts::SQRT_2),
        ];
        for (name, value) in want {
            let (_, c) =
                module.constants.iter().find(|(_, c)| c.name.as_deref() == Some(name)).unwrap();
            match module.global_expressions[c.init] {
                naga::Expression::Literal(naga::Literal::F64(v)) => {
                    assert_eq!(v.to_bits(), value.to_bits(), "{name}")
                }
                ref other => panic!("{name}: {other:?}"),
            }
        }
        let (_, c) =
            module.constants.iter().find(|(_, c)| c.name.as_deref() == Some("M_LN2_HI")).unwrap();
        let naga::Expression::Literal(naga::Literal::F64(hi)) = module.global_expressions[c.init]
        else {
            panic!()
        };
        let (_, c) =
            module.constants.iter().find(|(_, c)| c.name.as_deref() == Some("M_LN2_LO")).unwrap();
        let naga::Expression::Literal(naga::Literal::F64(lo)) = module.global_expressions[c.init]
        else {
            panic!()
        };
        assert_eq!(hi + lo, std::f64::consts::LN_2);
        assert_eq!(hi.to_bits() & 0x7ff, 0, "ln2_hi must end in zero bits so k ln2_hi is exact");
    }
}
