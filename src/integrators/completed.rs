//! The image of the iterations completed so far, kept for an interrupt that will not
//! wait for the iteration under way (a second Ctrl-C): the command line writes it and
//! quits while the render's threads are still busy.
//!
//! The render loop [`Completed::keep`]s a snapshot after every iteration that took at
//! least a hundred times the snapshot's own cost (so snapshots cost at most 1% of the
//! render; after shorter ones it says [`Completed::passed`], and an abort then lets the
//! short iteration under way finish), and claims
//! the right to write when it ends ([`Completed::finishing`]); an abort claims it with
//! [`Completed::abort`]. Whoever claims first writes, so the final save (image,
//! checkpoint, ERRORS.csv) is never cut short by an abort, and an abort's image is
//! never overwritten by a half-finished render.

use super::report::ErrorRow;
use crate::imageio::RgbImage;
use std::sync::Mutex;

/// What an abort writes: the image and error rows after the last completed iteration.
#[derive(Clone, Debug)]
pub struct Snapshot {
    pub image: RgbImage,
    pub errors: Vec<ErrorRow>,
    /// Iterations (passes) in the image, this run's and a resumed checkpoint's.
    pub iterations: u32,
}

#[derive(Debug, Default)]
enum Phase {
    #[default]
    Rendering,
    /// The render loop ended and is saving its own results.
    Finishing,
    /// An abort took the snapshot; the render must write nothing more.
    Aborted,
}

#[derive(Debug, Default)]
struct State {
    phase: Phase,
    snapshot: Option<Snapshot>,
    /// The snapshot is of the last completed iteration (not an earlier one).
    fresh: bool,
}

/// Shared between the render loop and whoever handles an abort.
#[derive(Debug, Default)]
pub struct Completed(Mutex<State>);

/// What [`Completed::abort`] found.
#[derive(Debug)]
pub enum Abort {
    /// The render was mid-iteration: this is the last completed state (none when no
    /// iteration had finished), and the render will write nothing more.
    Now(Option<Box<Snapshot>>),
    /// The render already finished its iterations and is saving: let it finish.
    Saving,
    /// The iterations are too short to be worth a snapshot each: the one under way
    /// ends soon, and the render then saves as after a first interrupt.
    Soon,
}

impl Completed {
    fn state(&self) -> std::sync::MutexGuard<'_, State> {
        // A panic while holding the lock leaves plain data behind: still usable.
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Keeps the state after an iteration (the render loop, between iterations).
    pub fn keep(&self, snapshot: Snapshot) {
        let mut s = self.state();
        if matches!(s.phase, Phase::Rendering) {
            (s.snapshot, s.fresh) = (Some(snapshot), true);
        }
    }

    /// An iteration completed without a snapshot (it was short).
    pub fn passed(&self) {
        self.state().fresh = false;
    }

    /// The render loop has ended: true when it may save its results, false when an
    /// abort came first (its snapshot is being written instead).
    pub fn finishing(&self) -> bool {
        let mut s = self.state();
        match s.phase {
            Phase::Aborted => false,
            _ => {
                s.phase = Phase::Finishing;
                true
            }
        }
    }

    /// Stops the render's own saving (unless it has begun) and hands over the last
    /// completed state.
    pub fn abort(&self) -> Abort {
        let mut s = self.state();
        match s.phase {
            Phase::Finishing => Abort::Saving,
            Phase::Rendering if !s.fresh && s.snapshot.is_some() => Abort::Soon,
            Phase::Aborted | Phase::Rendering => {
                s.phase = Phase::Aborted;
                Abort::Now(s.snapshot.take().map(Box::new))
            }
        }
    }

    /// Whether an abort has taken over.
    pub fn aborted(&self) -> bool {
        matches!(self.state().phase, Phase::Aborted)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn snap(iterations: u32) -> Snapshot {
        Snapshot { image: RgbImage::new(1, 1), errors: Vec::new(), iterations }
    }

    #[test]
    fn an_abort_mid_iteration_takes_the_last_kept_state_and_stops_the_renders_saving() {
        let c = Completed::default();
        c.keep(snap(1));
        c.keep(snap(2));
        match c.abort() {
            Abort::Now(Some(s)) => assert_eq!(s.iterations, 2),
            other => panic!("{other:?}"),
        }
        c.keep(snap(3));
        assert!(!c.finishing(), "the render must not save over the aborted image");
        assert!(c.aborted());
    }

    #[test]
    fn an_abort_while_the_render_saves_waits_for_it() {
        let c = Completed::default();
        c.keep(snap(4));
        assert!(c.finishing());
        assert!(matches!(c.abort(), Abort::Saving));
        assert!(!c.aborted());
    }

    #[test]
    fn an_abort_after_short_iterations_without_snapshots_lets_the_render_save() {
        let c = Completed::default();
        c.keep(snap(1));
        c.passed();
        assert!(matches!(c.abort(), Abort::Soon));
        assert!(c.finishing(), "the render saves its own, newer, state");
    }

    #[test]
    fn an_abort_before_any_iteration_has_nothing_to_write() {
        assert!(matches!(Completed::default().abort(), Abort::Now(None)));
    }
}
