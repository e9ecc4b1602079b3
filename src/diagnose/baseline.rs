//! The first stage of a diagnosis: the thesis's model with no candidate effect, its shared
//! parameters fitted jointly to every condition. Its optimum starts every nested candidate
//! and the motion screen, and its gap is what a candidate must close.

use super::run::Run;
use crate::calibrate::{Fit, Model, Search, Space};

/// The fitted baseline: its space (the shared parameters alone) and its fit on the fit
/// streams.
#[derive(Clone, Debug)]
pub struct Baseline {
    pub space: Space,
    pub fit: Fit,
}

impl Baseline {
    /// The baseline's parameter names and fitted values, for starting other models from it.
    pub fn names(&self) -> Vec<&'static str> {
        self.space.names()
    }
}

/// Fit the baseline: a differential evolution over the shared parameters' box on random
/// stream 0, then the polish at the full budget.
pub fn fit_baseline(run: &Run, log: &mut dyn FnMut(String)) -> anyhow::Result<Baseline> {
    let space = Space::new(run.shared.clone(), &[], run.conditions());
    let model =
        Model { space: &space, targets: &run.targets, starts: Vec::new(), search: Search::Global { stream: 0 } };
    let fit = run.solver.fit(&run.sim, &[model], log)?.remove(0);
    log(format!("diagnose: baseline: SSE {:.1} %² (fit streams)", fit.value));
    Ok(Baseline { space, fit })
}
