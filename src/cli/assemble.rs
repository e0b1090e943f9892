//! `radiosity assemble`: the matrix K as a NumPy file.

use radiosity::error::{Error, Result};
use radiosity::operator::OperatorChoice;
use radiosity::pipeline;

use super::args::AssembleArgs;

pub(crate) fn run_assemble(args: &AssembleArgs) -> Result<()> {
    let mut options = args.geometry.options()?;
    args.device.fill(&mut options);
    args.operator.fill(&mut options);
    if args.output.is_none() && args.save.is_none() {
        return Err(Error::InvalidParameter {
            name: "output",
            value: "none".into(),
            reason: "give --output K.npy (the dense matrix), --save OP.bin (the operator, for \
                     solve --operator-file), or both"
                .into(),
        });
    }
    if args.output.is_some() {
        if options.operator == OperatorChoice::Compressed {
            return Err(Error::InvalidParameter {
                name: "output",
                value: args.output.clone().unwrap_or_default(),
                reason: "the .npy file holds the dense matrix: leave out --operator compressed, \
                         or save the compressed operator with --save alone"
                    .into(),
            });
        }
        options.operator = OperatorChoice::Dense;
    }
    let config = args.geometry.scene.config_of(&options)?;
    let problem = pipeline::build(&config)?;
    super::output::print_notes(&problem.scene);
    let built = pipeline::build_operator(&config, &problem)?;
    if let (Some(path), Some(k)) = (&args.output, built.matrix()) {
        radiosity::report::write_npy(path, k.dof(), k.as_slice())?;
        eprintln!("wrote K ({} x {}, float64, rho/pi included) to {path}", k.dof(), k.dof());
    }
    if let Some(path) = &args.save {
        pipeline::save_operator(std::path::Path::new(path), &built, &config, &problem)?;
        let summary = built.summary(&config);
        eprintln!(
            "saved the {} operator ({} unknowns, {:.1} MB, built in {:.2} s) to {path}",
            summary.operator,
            problem.disc.dof(),
            summary.operator_bytes as f64 / 1e6,
            summary.setup_seconds
        );
    }
    Ok(())
}
