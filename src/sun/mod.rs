//! Direct sunlight (`mod.rs` only declares and re-exports): the sun as a parallel source given
//! by its zenith and azimuth, and a sky beside it (`sun/sources.rs`), a day of them from a file
//! (`sun/positions.rs`), and the exactly sunlit part of each element (`sun/shadows.rs`): every
//! occluder's shadow cast along the sun's direction onto the element's plane, subtracted as
//! convex polygons (the same exact polygon machinery as the pair plan's, with a parallel
//! projection instead of a central one).

mod positions;
mod shadows;
mod sources;

pub use positions::{Moment, read_moments};
pub use shadows::{Sunlit, sunlit};
pub use sources::{DEFAULT_X_AZIMUTH, Sources, Sun};
