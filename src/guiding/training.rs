//! Training a guide over a render's passes: rounds of 1, 2, 4, … passes (Müller et
//! al.'s doubling), each recording what the camera subpaths found into the tree's
//! building half while its sampling half (the rounds before) guides them; after
//! [`ROUNDS`] rounds it is frozen. A guide for light subpaths trains its importance
//! tree in the same rounds, from the same camera subpaths: where they arrived from at
//! each vertex past the first, weighed by their throughput there (Vorba et al. 2014's
//! importons).
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

/// What a pass's camera subpaths record, in pixel order: the light found past their
/// vertices (for the camera's guide) and the importance arriving at them (for the
/// light subpaths').
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Records {
    pub radiance: Vec<Record>,
    pub importance: Vec<Record>,
}

impl Records {
    /// Appends `other`'s records after these.
    pub fn append(&mut self, mut other: Records) {
        self.radiance.append(&mut other.radiance);
        self.importance.append(&mut other.importance);
    }
}

/// A guide being trained, or trained (a checkpoint saves it, so that `--resume` need
/// not replay the training).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Guide {
    tree: Arc<STree>,
    /// The incident importance light subpaths draw from, if they are guided.
    /// (Checkpoints from before it existed have none.)
    #[serde(default)]
    importance: Option<Arc<STree>>,
    lo: Vec3,
    hi: Vec3,
    /// Passes recorded (0..=[`TRAINING_PASSES`]).
    recorded: u32,
}

impl Guide {
    /// An untrained guide over the box `[lo, hi]`, with an importance tree for light
    /// subpaths if `importance`.
    pub fn new(lo: Vec3, hi: Vec3, importance: bool) -> Guide {
        let importance = importance.then(|| Arc::new(STree::new(lo, hi)));
        Guide { tree: Arc::new(STree::new(lo, hi)), importance, lo, hi, recorded: 0 }
    }

    /// The tree camera subpaths sample from (its sampling trees, those of the rounds
    /// ended).
    pub fn tree(&self) -> Arc<STree> {
        self.tree.clone()
    }

    /// The importance tree light subpaths sample from, if the guide has one.
    pub fn importance(&self) -> Option<Arc<STree>> {
        self.importance.clone()
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
        *self = Guide::new(self.lo, self.hi, self.importance.is_some());
    }

    /// Adds a pass's records of light and of importance, each in the order given (the
    /// importance records are dropped without an importance tree); a round ends after
    /// 1, 3, 7, … passes recorded.
    pub fn add_pass(&mut self, records: &Records) {
        self.recorded += 1;
        let split = (self.recorded + 1)
            .is_power_of_two()
            .then(|| (SPLIT_RECORDS * (self.recorded.div_ceil(2) as f64).sqrt()) as u64);
        learn(Arc::make_mut(&mut self.tree), &records.radiance, split);
        if let Some(t) = &mut self.importance {
            learn(Arc::make_mut(t), &records.importance, split);
        }
    }
}

/// Adds records to a tree, then ends its round if `split` (the round's split threshold)
/// says so.
fn learn(tree: &mut STree, records: &[Record], split: Option<u64>) {
    for r in records {
        tree.record(r.p, r.d, r.energy as f64);
    }
    if let Some(split) = split {
        tree.end_round(split, RHO);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounds_end_after_one_three_seven_passes_and_training_stops() {
        let mut g = Guide::new(Vec3::ZERO, Vec3::ONE, true);
        let light = Record { p: Vec3::splat(0.5), d: Vec3::Z, energy: 1.0 };
        let seen = Record { d: -Vec3::Z, energy: 2.0, ..light };
        let (mut guided, mut importance) = (vec![], vec![]);
        for pass in 0..40 {
            assert_eq!(g.trains_on(pass), pass < TRAINING_PASSES);
            if g.trains_on(pass) {
                g.add_pass(&Records { radiance: vec![light; 10], importance: vec![seen; 3] });
            }
            guided.push(g.tree().sampling(Vec3::splat(0.5)).total());
            importance.push(g.importance().unwrap().sampling(Vec3::splat(0.5)).total());
        }
        // The sampling trees change only as a round ends: after passes 0, 2, 6, 14, 30.
        let changes = |v: &[f64]| (1..v.len()).filter(|&k| v[k] != v[k - 1]).collect::<Vec<usize>>();
        assert_eq!((guided[0], importance[0]), (10.0, 6.0));
        assert_eq!(changes(&guided), [2, 6, 14, 30]);
        assert_eq!(changes(&importance), [2, 6, 14, 30]);
        // Each tree learns its own records' directions.
        let i = g.importance().unwrap();
        assert!(i.sampling(Vec3::splat(0.5)).pdf(-Vec3::Z) > 1.0 && i.sampling(Vec3::splat(0.5)).pdf(Vec3::Z) == 0.0);
        assert!(!g.behind(40) && g.recorded() == TRAINING_PASSES);
        g.reset();
        assert!(g.behind(1) && !g.behind(0) && g.tree().sampling(Vec3::ZERO).total() == 0.0);
        assert_eq!(g.importance().unwrap().sampling(Vec3::ZERO).total(), 0.0);
        assert!(Guide::new(Vec3::ZERO, Vec3::ONE, false).importance().is_none());
    }
}
