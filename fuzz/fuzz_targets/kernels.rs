//! The collocation kernels on arbitrary finite input that meets their documented preconditions
//! (node above the element's plane, unit normal, a triangle with area, lengths in units of the
//! element's size as the assembly passes them): the result must be finite, and no input may panic.

#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../bodies/kernels.rs"]
mod body;

fuzz_target!(|data: &[u8]| body::check(data));
