//! The commands of the `pbrt-sppm` binary other than `render` (which is [`crate::job`]):
//! what they compute, apart from the rendering library. The binary parses the command
//! line and prints; these build the reports, ray answers, exports and cluster scripts.

pub mod check;
pub mod export;
pub mod farm;
pub mod fuzzing;
pub mod trace;
