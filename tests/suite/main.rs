//! The integration tests, one binary (one link of the crate, wgpu and faer; one GPU context and
//! its compiled kernels shared by every GPU test). `cargo test --release` runs them beside the
//! library's unit tests; `cargo test --release --test suite gpu::` picks a module.
//!
//! - `cli`, `cli_operator`, `scenes`, `scene_bands`: the real binary against the command line's
//!   contract (ARCHITECTURE.md, "The command line");
//! - `estimates`, `generated`, `properties`: the view factors' estimates and the operator's
//!   invariants on scenes generated from seeds, and property tests;
//! - `fuzz_replay`: the fuzz targets' checks on stable;
//! - `gpu`, `gpu_clipping`: the GPU against the CPU (lavapipe in CI);
//! - `module_graph`: which module may use which;
//! - `sun`: the sunlit parts against the analytic shadow of a box and the energy they carry.
//!
//! The MPI tests are a binary of their own (`tests/mpi.rs`, feature `mpi`).

mod common;

mod cli;
mod cli_operator;
mod estimates;
mod fuzz_replay;
mod generated;
mod gpu;
mod gpu_clipping;
mod module_graph;
mod properties;
mod scene_bands;
mod scenes;
mod sun;
