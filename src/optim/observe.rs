//! The side jobs of an optimisation loop as observers (after argmin's executor and
//! observers): the solver only steps, [`drive`] runs it, and what happens around each
//! generation (logging, checkpoints, progress, Ctrl-C) is a list of [`Observer`]s the caller
//! composes. `optim::runner` builds its run folder from them.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

use super::nsga2::{save_checkpoint, BatchProblem, GenerationStats, Nsga2, State, Termination};

/// What an observer asks of the loop after a generation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    Continue,
    /// End the run now (e.g. Ctrl-C): every observer then sees [`Ending::Stopped`].
    Stop,
}

/// How a driven run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ending {
    /// The solver's own criterion.
    Terminated(Termination),
    /// An observer asked to stop.
    Stopped,
}

pub trait Observer {
    /// After every generation, in the order the observers were given; an error ends the run
    /// with that error (the later observers do not see the generation).
    fn observe(&mut self, state: &State, stats: &GenerationStats) -> anyhow::Result<Flow>;
    /// Once, when the run ends (not after an error).
    fn finish(&mut self, _state: &State, _ending: Ending) -> anyhow::Result<()> {
        Ok(())
    }
}

/// Step `ga` from `state` until it terminates or an observer stops it; every observer sees
/// each generation and the end.
pub fn drive(
    ga: &Nsga2,
    state: &mut State,
    problem: &mut impl BatchProblem,
    observers: &mut [&mut dyn Observer],
) -> anyhow::Result<Ending> {
    let ending = loop {
        if let Some(t) = ga.should_stop(state) {
            break Ending::Terminated(t);
        }
        let stats = ga.step(state, problem);
        let mut flow = Flow::Continue;
        for o in observers.iter_mut() {
            if o.observe(state, &stats)? == Flow::Stop {
                flow = Flow::Stop;
            }
        }
        if flow == Flow::Stop {
            break Ending::Stopped;
        }
    };
    for o in observers.iter_mut() {
        o.finish(state, ending)?;
    }
    Ok(ending)
}

/// The state saved atomically every `every` generations and when the run ends, however it
/// ends: a resume continues from the last one exactly.
pub struct Checkpoints {
    pub path: PathBuf,
    pub every: u64,
}

impl Observer for Checkpoints {
    fn observe(&mut self, state: &State, _: &GenerationStats) -> anyhow::Result<Flow> {
        if state.generation.is_multiple_of(self.every.max(1)) {
            save_checkpoint(&self.path, state)?;
        }
        Ok(Flow::Continue)
    }
    fn finish(&mut self, state: &State, _: Ending) -> anyhow::Result<()> {
        save_checkpoint(&self.path, state)
    }
}

/// Set by the Ctrl-C handler: every running optimisation stops after its generation.
pub static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Install the Ctrl-C handler once (later calls are no-ops).
pub fn install_interrupt_handler() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = ctrlc::set_handler(|| INTERRUPTED.store(true, Ordering::SeqCst));
    });
}

/// Stops the run after the generation in which Ctrl-C was pressed (put it last, so the
/// other observers record that generation first).
pub struct Interrupt;

impl Observer for Interrupt {
    fn observe(&mut self, _: &State, _: &GenerationStats) -> anyhow::Result<Flow> {
        Ok(if INTERRUPTED.load(Ordering::SeqCst) { Flow::Stop } else { Flow::Continue })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::nsga2::Config;
    use crate::optim::test_problems::Zdt1;

    fn ga(generations: u64) -> Nsga2 {
        Nsga2::new(Config { pop: 12, max_generations: generations, seed: 3, ..Config::default() })
    }

    /// Records what it sees, and stops the run at a given generation.
    struct Probe {
        seen: Vec<u64>,
        stop_at: Option<u64>,
        ended: Option<Ending>,
    }

    impl Observer for Probe {
        fn observe(&mut self, state: &State, stats: &GenerationStats) -> anyhow::Result<Flow> {
            assert_eq!(state.generation, stats.generation);
            self.seen.push(stats.generation);
            Ok(if Some(stats.generation) == self.stop_at { Flow::Stop } else { Flow::Continue })
        }
        fn finish(&mut self, _: &State, ending: Ending) -> anyhow::Result<()> {
            self.ended = Some(ending);
            Ok(())
        }
    }

    #[test]
    fn every_observer_sees_every_generation_and_the_end() {
        let ga = ga(5);
        let mut problem = Zdt1::default();
        let mut state = ga.init(&mut problem);
        let (mut a, mut b) =
            (Probe { seen: vec![], stop_at: None, ended: None }, Probe { seen: vec![], stop_at: None, ended: None });
        let ending = drive(&ga, &mut state, &mut problem, &mut [&mut a, &mut b]).unwrap();
        assert_eq!(ending, Ending::Terminated(Termination::MaxGenerations));
        assert_eq!(a.seen, vec![1, 2, 3, 4, 5]);
        assert_eq!(b.seen, a.seen);
        assert_eq!((a.ended, b.ended), (Some(ending), Some(ending)));
    }

    #[test]
    fn an_observer_stops_the_run_and_the_checkpoint_resumes_it_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("checkpoint.json");
        let ga = ga(6);
        let mut problem = Zdt1::default();
        // stopped after generation 2; the checkpoint (every 4) is written at the end anyway
        let mut state = ga.init(&mut problem);
        let mut stop = Probe { seen: vec![], stop_at: Some(2), ended: None };
        let mut ck = Checkpoints { path: path.clone(), every: 4 };
        let ending = drive(&ga, &mut state, &mut problem, &mut [&mut ck, &mut stop]).unwrap();
        assert_eq!(ending, Ending::Stopped);
        assert_eq!(stop.seen, vec![1, 2]);
        let mut resumed = crate::optim::nsga2::load_checkpoint(&path).unwrap();
        assert_eq!(resumed.generation, 2);
        drive(&ga, &mut resumed, &mut problem, &mut []).unwrap();
        // the same run without a stop
        let mut straight = ga.init(&mut problem);
        drive(&ga, &mut straight, &mut problem, &mut []).unwrap();
        assert_eq!(resumed, straight);
    }

    #[test]
    fn an_observer_error_ends_the_run_with_it() {
        struct Fails;
        impl Observer for Fails {
            fn observe(&mut self, _: &State, _: &GenerationStats) -> anyhow::Result<Flow> {
                anyhow::bail!("disk full")
            }
        }
        let ga = ga(5);
        let mut problem = Zdt1::default();
        let mut state = ga.init(&mut problem);
        let e = drive(&ga, &mut state, &mut problem, &mut [&mut Fails]).unwrap_err();
        assert_eq!(e.to_string(), "disk full");
        assert_eq!(state.generation, 1);
    }
}
