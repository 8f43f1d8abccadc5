//! Interrupts during a render: Ctrl-C (SIGINT), SIGTERM and SIGHUP.
//!
//! - The first lets the iteration under way finish, then saves everything (image,
//!   checkpoint, part, ERRORS.csv) and exits with status 130.
//! - The second stops at once: the main thread writes the image and ERRORS.csv of the
//!   iterations completed so far (atomically, as every output) and exits 130. If the
//!   render had already finished its iterations and is saving, it is let finish.
//! - A third quits without writing anything more, and says so.
//!
//! GNU `timeout -s INT` signals the process twice at once, and a user may press
//! Ctrl-C twice: neither loses the iterations done.

use crate::print::say;
use pbrt_sppm::integrators::completed::Completed;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};

/// What the render loop and the main thread hear from the signal handler.
pub enum Event {
    /// A second interrupt: stop now.
    Abort,
    /// The render (and its own saving) is over.
    Done,
}

pub struct Signals {
    /// Raised by the first interrupt: stop after the iteration under way.
    pub stop: Arc<AtomicBool>,
    /// The last completed iteration's image, for an abort.
    pub completed: Arc<Completed>,
    pub events: Receiver<Event>,
    /// For the render thread to say it is done.
    pub done: Sender<Event>,
}

/// Tells the main thread the render is over when dropped (at its end, or unwinding
/// from a panic).
pub struct DoneOnDrop<'a>(pub &'a Sender<Event>);

impl Drop for DoneOnDrop<'_> {
    fn drop(&mut self) {
        let _ = self.0.send(Event::Done);
    }
}

/// Installs the handler; a failure to install is a warning (an interrupt then kills the
/// render as it would any program).
pub fn install(quiet: bool) -> Signals {
    let stop = Arc::new(AtomicBool::new(false));
    let (tx, events) = channel();
    let done = tx.clone();
    let (raised, count) = (stop.clone(), AtomicU32::new(0));
    let installed = ctrlc::set_handler(move || match count.fetch_add(1, Ordering::SeqCst) {
        0 => {
            raised.store(true, Ordering::SeqCst);
            if !quiet {
                say!(
                    "\ninterrupted: finishing this iteration, then saving (interrupt again to stop now and keep the iterations done)"
                );
            }
        }
        1 => {
            // The main thread writes; this handler stays free to hear a third signal.
            let _ = tx.send(Event::Abort);
        }
        _ => {
            say!(
                "\ninterrupted a third time: quitting without writing the image (files already written are left as they were)"
            );
            std::process::exit(130);
        }
    });
    if let Err(e) = installed
        && !quiet
    {
        say!("warning: cannot catch interrupts ({e}); an interrupted render will be lost");
    }
    Signals { stop, completed: Arc::new(Completed::default()), events, done }
}
