//! Several optimisation runs (conveyor angles, seeds, parameter grids) in threads, their
//! generations merged into one engine call: each run's `evaluate` deposits its population
//! and waits; when every active run has deposited, the last one in evaluates them all with
//! `evaluate_groups` (one GPU job where the batch-wide physics is shared) and wakes the
//! others. A run that finishes leaves the group, so the others never wait for it.

use std::sync::{Condvar, Mutex};

use crate::engine::{BatchEvaluator, Evaluation};
use crate::model::{Design, Invalid, Scenario};

type Batch = Vec<Result<Evaluation, Invalid>>;

struct Inner {
    active: usize,
    pending: Vec<Option<(Scenario, Vec<Design>)>>,
    results: Vec<Option<Batch>>,
}

pub struct Lockstep<'a> {
    engine: &'a dyn BatchEvaluator,
    inner: Mutex<Inner>,
    ready: Condvar,
}

impl<'a> Lockstep<'a> {
    pub fn new(engine: &'a dyn BatchEvaluator, members: usize) -> Self {
        Lockstep {
            engine,
            inner: Mutex::new(Inner { active: members, pending: vec![None; members], results: vec![None; members] }),
            ready: Condvar::new(),
        }
    }

    /// The evaluator run `slot` uses; dropping it leaves the group.
    pub fn member(&'a self, slot: usize) -> Member<'a> {
        Member { group: self, slot }
    }

    /// Evaluate every deposited batch if all active members have deposited.
    fn flush_if_complete(&self, inner: &mut Inner) {
        let waiting = inner.pending.iter().filter(|p| p.is_some()).count();
        if waiting == 0 || waiting < inner.active {
            return;
        }
        let slots: Vec<usize> = (0..inner.pending.len()).filter(|&i| inner.pending[i].is_some()).collect();
        let groups: Vec<(Scenario, Vec<Design>)> =
            slots.iter().map(|&i| inner.pending[i].take().expect("deposited")).collect();
        let results = self.engine.evaluate_groups(&groups);
        for (slot, r) in slots.into_iter().zip(results) {
            inner.results[slot] = Some(r);
        }
        self.ready.notify_all();
    }
}

pub struct Member<'a> {
    group: &'a Lockstep<'a>,
    slot: usize,
}

impl BatchEvaluator for Member<'_> {
    fn backend(&self) -> &'static str {
        self.group.engine.backend()
    }
    fn device(&self) -> String {
        self.group.engine.device()
    }
    fn evaluate(&self, scenario: &Scenario, designs: &[Design]) -> Batch {
        let g = self.group;
        let mut inner = g.inner.lock().expect("lockstep lock");
        inner.pending[self.slot] = Some((scenario.clone(), designs.to_vec()));
        g.flush_if_complete(&mut inner);
        loop {
            if let Some(r) = inner.results[self.slot].take() {
                return r;
            }
            inner = g.ready.wait(inner).expect("lockstep wait");
        }
    }
}

impl Drop for Member<'_> {
    fn drop(&mut self) {
        let g = self.group;
        let mut inner = g.inner.lock().unwrap_or_else(|e| e.into_inner());
        inner.active -= 1;
        g.flush_if_complete(&mut inner);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::{particle_engine, EngineKind};

    #[test]
    fn members_get_their_own_results_and_leaving_does_not_block() {
        let e = particle_engine(EngineKind::Cpu);
        let group = Lockstep::new(&e, 3);
        let mut s = Scenario::lunar();
        s.sim.particles = 10;
        let d = Design::lunar_solution_c();
        std::thread::scope(|scope| {
            for slot in 0..3 {
                let (group, s) = (&group, s.clone());
                scope.spawn(move || {
                    let m = group.member(slot);
                    // member 0 leaves after one batch, the others do three
                    let rounds = if slot == 0 { 1 } else { 3 };
                    for _ in 0..rounds {
                        let designs = vec![d; slot + 1];
                        assert_eq!(m.evaluate(&s, &designs).len(), slot + 1);
                    }
                });
            }
        });
    }
}
