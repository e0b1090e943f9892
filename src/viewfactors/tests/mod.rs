//! The view factors against closed forms and references, and the vector lanes and inclusion and
//! exclusion of shadows against the scalar closed forms they replace.
//!
//! By concept: the fixture the tests compute on (`fixture.rs`); whole matrices against closed
//! forms (`closed_forms.rs`) and closed scenes' row sums and reciprocity (`closed_scenes.rs`);
//! sky view factors, conditioning and thresholds (`closure.rs`);
//! entries where elements or occluders touch (`contacts.rs`); the estimates and bounds that
//! choose the work (`estimates.rs`); shadows, openings and the lanes against the scalar closed
//! forms (`shadows.rs`); partly shadowed pairs against brute force and Monte Carlo
//! (`references.rs`).

mod closed_forms;
mod closed_scenes;
mod closure;
mod contacts;
mod estimates;
mod fixture;
mod references;
mod shadows;

pub(super) use fixture::Fixture;
