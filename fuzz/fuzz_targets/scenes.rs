//! Whole scenes from arbitrary coordinates through the public entry points: validation either
//! rejects the input with an error or the pair plan and assembly give a matrix whose entries are
//! finite and whose rows of K/rho sum to at most 1 (to 1e-3). No input may panic.

#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../bodies/scenes.rs"]
mod body;

fuzz_target!(|data: &[u8]| body::check(data));
