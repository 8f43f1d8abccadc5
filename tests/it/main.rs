//! The one integration-test binary (one link step keeps 2-core CI fast).

mod alpha;
mod bad_inputs;
mod camera_image;
mod checkpoint;
mod common;
mod converge;
mod directives;
mod fixes;
mod fuzz_regressions;
mod hostile;
mod imgtool;
mod instancing;
mod interfaces;
mod intersect;
mod layout;
mod mitsuba;
mod pbrt_refs;
mod real_scenes;
mod render;
mod sampling;
mod shapes;
mod shards;
mod slurm;
mod stability;
mod tokenizer;
mod truncation;
