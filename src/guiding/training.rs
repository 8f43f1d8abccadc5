//! Training a guide over a render's passes: rounds of 1, 2, 4, … passes (Müller et
//! al.'s doubling), each recording what the camera subpaths found into the tree's
//! building half while its sampling half (the rounds before) guides them; after
//! [`ROUNDS`] rounds it is frozen.
//!
//! The guide a pass samples from is a function of the passes before it and nothing
//! else: records are added in pixel order, whatever the thread count, so a render
//! that starts part way (a shard, `--resume`) replays the training passes and samples
//! from the same tree as a render from pass 0.

use super::STree;
use glam::Vec3;
use std::sync::Arc;

/// Rounds of training.
pub const ROUNDS: u32 = 5;

/// Passes that train: rounds of 1, 2, 4, 8 and 16.
pub const TRAINING_PASSES: u32 = (1 << ROUNDS) - 1;

/// A leaf splits past this many records times the square root of the round's passes
/// (Müller et al.'s c·√(2ᵏ), with a smaller c: our images are smaller than theirs,
/// and fewer records per pass must still resolve a room's walls).
const SPLIT_RECORDS: f64 = 4000.0;

/// A directional quadrant splits above this share of its tree's energy (Müller et
/// al.'s ρ).
const RHO: f64 = 0.01;

/// An estimate of the light arriving at `p` from direction `d`, divided by the density
/// the direction was drawn with (what a directional tree sums).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    pub p: Vec3,
    pub d: Vec3,
    pub energy: f32,
}

/// A guide being trained, or trained (a checkpoint saves it, so that `--resume` need
/// not replay the training).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Guide {
    tree: Arc<STree>,
    lo: Vec3,
    hi: Vec3,
    /// Passes recorded (0..=[`TRAINING_PASSES`]).
    recorded: u32,
}

impl Guide {
    /// An untrained guide over the box `[lo, hi]`.
    pub fn new(lo: Vec3, hi: Vec3) -> Guide {
        Guide { tree: Arc::new(STree::new(lo, hi)), lo, hi, recorded: 0 }
    }

    /// The tree passes sample from (its sampling trees, those of the rounds ended).
    pub fn tree(&self) -> Arc<STree> {
        self.tree.clone()
    }

    /// Whether pass `pass`'s camera subpaths record for the guide: it is the next pass
    /// the guide waits for, within the training.
    pub fn trains_on(&self, pass: u32) -> bool {
        pass == self.recorded && pass < TRAINING_PASSES
    }

    /// Whether the guide lacks some of the training passes before `pass` (a render that
    /// starts there must replay them).
    pub fn behind(&self, pass: u32) -> bool {
        self.recorded < pass.min(TRAINING_PASSES)
    }

    /// Passes recorded so far.
    pub fn recorded(&self) -> u32 {
        self.recorded
    }

    /// Back to untrained.
    pub fn reset(&mut self) {
        *self = Guide::new(self.lo, self.hi);
    }

    /// Adds a pass's records, in the order given; a round ends after 1, 3, 7, …
    /// passes recorded.
    pub fn add_pass(&mut self, records: &[Record]) {
        let tree = Arc::make_mut(&mut self.tree);
        for r in records {
            tree.record(r.p, r.d, r.energy as f64);
        }
        self.recorded += 1;
        if (self.recorded + 1).is_power_of_two() {
            let round = self.recorded.div_ceil(2);
            tree.end_round((SPLIT_RECORDS * (round as f64).sqrt()) as u64, RHO);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounds_end_after_one_three_seven_passes_and_training_stops() {
        let mut g = Guide::new(Vec3::ZERO, Vec3::ONE);
        let light = Record { p: Vec3::splat(0.5), d: Vec3::Z, energy: 1.0 };
        let mut guided = vec![];
        for pass in 0..40 {
            assert_eq!(g.trains_on(pass), pass < TRAINING_PASSES);
            if g.trains_on(pass) {
                g.add_pass(&[light; 10]);
            }
            guided.push(g.tree().sampling(Vec3::splat(0.5)).total());
        }
        // The sampling tree changes only as a round ends: after passes 0, 2, 6, 14, 30.
        let changes: Vec<usize> = (1..guided.len()).filter(|&k| guided[k] != guided[k - 1]).collect();
        assert_eq!(guided[0], 10.0);
        assert_eq!(changes, [2, 6, 14, 30]);
        assert!(!g.behind(40) && g.recorded() == TRAINING_PASSES);
        g.reset();
        assert!(g.behind(1) && !g.behind(0) && g.tree().sampling(Vec3::ZERO).total() == 0.0);
    }
}
