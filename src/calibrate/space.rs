//! The calibration's parameter space: the shared collision/drag parameters ([`Param`]) and
//! the switched-on effects' own parameters ([`EffectKind`]), searched in a unit box.

use super::condition::Condition;
use super::param::Param;
use super::varying::Varying;
use crate::model::effects::{EffectKind, MotionDirection};
use crate::model::Scenario;

/// The shared parameters the conditions call for: k_elastic, mu_fric, and k_drag when any
/// setup has drag.
pub fn shared_params(conditions: &[Condition]) -> Vec<Param> {
    let mut p = vec![Param::KElastic, Param::MuFric];
    if conditions.iter().any(Condition::has_drag) {
        p.push(Param::KDrag);
    }
    p
}

/// One model's parameters: `shared` first, then the effects' free parameters, then the
/// slopes of the shared parameters that vary across the conditions.
#[derive(Clone, Debug, PartialEq)]
pub struct Space {
    pub shared: Vec<Param>,
    /// The effects switched on (none for the baseline).
    pub effects: Vec<EffectKind>,
    /// The effects' fitted parameters, as (index into `effects`, parameter index): all of
    /// them, except sled-motion values that every condition states (`KnownMotion`) and
    /// those `pinned`.
    pub free: Vec<(usize, usize)>,
    /// Effect parameters held at a value instead of fitted, as (index into `effects`,
    /// parameter index, value): a search that scans a parameter over a grid holds it at
    /// each grid value in turn ([`Space::pin`]).
    pub pinned: Vec<(usize, usize, f64)>,
    /// The sled's return direction where a condition does not state it (`[measurement]
    /// motion_direction`); None is the model's default, down the slope. Not a fitted
    /// parameter: the motion screen tries each ([`Space::with_motion_direction`]).
    pub motion_direction: Option<MotionDirection>,
    /// Shared parameters that vary linearly with a condition's variable (a joint fit over
    /// regimes, [`Space::with_varying`]); each adds its slope as the space's last dimensions.
    pub varying: Vec<Varying>,
}

impl Space {
    pub fn new(mut shared: Vec<Param>, effects: &[EffectKind], conditions: &[Condition]) -> Self {
        if effects.contains(&EffectKind::QuadraticDrag) {
            // Schiller-Naumann drag replaces the linear law: k_drag would be a dead parameter
            // (the setups' own value only marks which of them are in air)
            shared.retain(|p| *p != Param::KDrag);
        }
        let mut free = Vec::new();
        for (k, e) in effects.iter().enumerate() {
            for i in 0..e.param_names().len() {
                let stated_everywhere =
                    *e == EffectKind::SledMotion && conditions.iter().all(|c| c.motion.get(i).is_some());
                if !stated_everywhere {
                    free.push((k, i));
                }
            }
        }
        Space {
            shared,
            effects: effects.to_vec(),
            free,
            pinned: Vec::new(),
            motion_direction: None,
            varying: Vec::new(),
        }
    }

    /// This space with `varying` shared parameters: each must be one of `shared`, at most
    /// once.
    pub fn with_varying(&self, varying: Vec<Varying>) -> Result<Space, String> {
        for (i, v) in varying.iter().enumerate() {
            if !self.shared.contains(&v.param) {
                return Err(format!("{} is not fitted here, so it cannot vary", v.param.name()));
            }
            if varying[..i].iter().any(|w| w.param == v.param) {
                return Err(format!("{} varies more than once", v.param.name()));
            }
        }
        Ok(Space { varying, ..self.clone() })
    }

    /// This space with its free parameter `name` held at `value` (no longer fitted; a
    /// value a condition states still wins for that condition, as it does for a fitted
    /// one). None when `name` is not one of the effects' free parameters.
    pub fn pin(&self, name: &str, value: f64) -> Option<Space> {
        let j = self.free.iter().position(|(k, i)| self.effects[*k].param_names()[*i] == name)?;
        let mut s = self.clone();
        let (k, i) = s.free.remove(j);
        s.pinned.push((k, i, value));
        Some(s)
    }

    /// This space with the sled returning along `direction` in every condition that does
    /// not state its own.
    pub fn with_motion_direction(&self, direction: MotionDirection) -> Space {
        Space { motion_direction: Some(direction), ..self.clone() }
    }

    /// Whether some condition leaves the return direction to the model (so that a search
    /// over it means something).
    pub fn direction_unstated(conditions: &[Condition]) -> bool {
        conditions.iter().any(|c| c.motion.direction.is_none())
    }

    pub fn dim(&self) -> usize {
        self.shared.len() + self.free.len() + self.varying.len()
    }

    pub fn bounds(&self) -> Vec<(f64, f64)> {
        let mut b: Vec<(f64, f64)> = self.shared.iter().map(|p| p.bounds()).collect();
        b.extend(self.free.iter().map(|(k, i)| self.effects[*k].search_bounds()[*i]));
        b.extend(self.varying.iter().map(Varying::slope_bounds));
        b
    }

    /// Parameter names, shared first (effect parameter names are unique across effects).
    pub fn names(&self) -> Vec<&'static str> {
        let mut n: Vec<&'static str> = self.shared.iter().map(|p| p.name()).collect();
        n.extend(self.free.iter().map(|(k, i)| self.effects[*k].param_names()[*i]));
        n.extend(self.varying.iter().map(Varying::slope_name));
        n
    }

    /// A start for this model from another model's point (`names`, `x`): each parameter
    /// takes the other model's value where it has one, an effect parameter the other lacks
    /// its neutral value, a slope the other lacks 0. From the baseline that is the baseline
    /// itself (a nested model); None when a parameter has no such value (quadratic drag).
    pub fn start_from(&self, names: &[&'static str], x: &[f64]) -> Option<Vec<f64>> {
        let own = self.names();
        let mut v = Vec::with_capacity(own.len());
        for (j, n) in own.iter().enumerate() {
            if let Some(p) = names.iter().position(|m| m == n) {
                v.push(x[p]);
            } else if j >= self.shared.len() + self.free.len() {
                v.push(0.0);
            } else if j >= self.shared.len() {
                let (k, i) = self.free[j - self.shared.len()];
                v.push(self.effects[k].neutral()?[i]);
            } else {
                return None;
            }
        }
        Some(v)
    }

    /// Condition `cond`'s scenario at parameters `x` (k_drag only where the setup has drag;
    /// sled motion as the setup states it, fitted where it does not; the setup's own effects
    /// stay unless the space fits them).
    pub fn scenario_at(&self, cond: &Condition, x: &[f64]) -> Scenario {
        let mut s = cond.base.clone();
        let slopes = &x[self.shared.len() + self.free.len()..];
        for (p, v) in self.shared.iter().zip(x) {
            if *p == Param::KDrag && !cond.has_drag() {
                continue;
            }
            let value = match self.varying.iter().position(|w| w.param == *p) {
                Some(i) => self.varying[i].value_in(*v, slopes[i], cond),
                None => *v,
            };
            p.apply(&mut s, value);
        }
        // the space's effects on top of the setup's own (none in a diagnosis; fixed in a fit)
        for (k, e) in self.effects.iter().enumerate() {
            let e = *e;
            let mut v: Vec<f64> = e.search_bounds().iter().map(|b| b.0).collect();
            for ((ek, i), xv) in self.free.iter().zip(&x[self.shared.len()..]) {
                if *ek == k {
                    v[*i] = *xv;
                }
            }
            for (pk, i, pv) in &self.pinned {
                if *pk == k {
                    v[*i] = *pv;
                }
            }
            if e == EffectKind::SledMotion {
                for (i, vi) in v.iter_mut().enumerate() {
                    if let Some(known) = cond.motion.get(i) {
                        *vi = known;
                    }
                }
            }
            e.apply(&mut s.effects, &v);
            if let (Some(m), Some(direction)) =
                (s.effects.sled_motion.as_mut(), cond.motion.direction.or(self.motion_direction))
            {
                m.direction = direction;
            }
        }
        s
    }

    pub fn from_unit(&self, u: &[f64]) -> Vec<f64> {
        u.iter().zip(self.bounds()).map(|(u, (l, h))| l + u.clamp(0.0, 1.0) * (h - l)).collect()
    }

    pub fn to_unit(&self, x: &[f64]) -> Vec<f64> {
        x.iter()
            .zip(self.bounds())
            .map(|(x, (l, h))| if h > l { ((x - l) / (h - l)).clamp(0.0, 1.0) } else { 0.0 })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibrate::condition::test3;

    #[test]
    fn a_pinned_parameter_leaves_the_search_and_holds_its_value() {
        let mut unstated = test3();
        unstated.motion = Default::default();
        let conds = vec![unstated.clone()];
        let space = Space::new(shared_params(&conds), &[EffectKind::SledMotion], &conds);
        let shared: Vec<&str> = space.shared.iter().map(|p| p.name()).collect();
        assert_eq!(space.names()[shared.len()..], ["delay_s", "return_speed_m_s"]);
        let pinned = space.pin("delay_s", 0.05).expect("delay_s is free");
        assert_eq!(pinned.names()[shared.len()..], ["return_speed_m_s"]);
        assert_eq!(pinned.dim(), space.dim() - 1);
        let mut x: Vec<f64> = space.shared.iter().map(|p| p.bounds().0).collect();
        x.push(0.4);
        let motion = pinned.scenario_at(&unstated, &x).effects.sled_motion.expect("a moving sled");
        assert_eq!((motion.delay_s, motion.return_speed_m_s), (0.05, 0.4));
        // a stated value wins over the pin, as it does over a fitted value
        let mut stated = unstated.clone();
        stated.motion.delay_s = Some(0.2);
        let motion = pinned.scenario_at(&stated, &x).effects.sled_motion.expect("a moving sled");
        assert_eq!(motion.delay_s, 0.2);
        // only a free parameter can be pinned
        assert!(pinned.pin("delay_s", 0.0).is_none());
        assert!(space.pin("k_elastic", 0.5).is_none());
    }

    /// The direction a setup states is the candidate's (it is not fitted); where none is
    /// stated the sled returns down the slope, or along the direction the space assumes.
    #[test]
    fn a_stated_return_direction_is_the_candidates() {
        use crate::model::effects::MotionDirection;
        let mut cond = test3();
        cond.motion = Default::default();
        let conds = vec![cond.clone()];
        let space = Space::new(shared_params(&conds), &[EffectKind::SledMotion], &conds);
        let mut x: Vec<f64> = space.shared.iter().map(|p| p.bounds().0).collect();
        x.extend([0.0, 0.4]);
        let motion = space.scenario_at(&cond, &x).effects.sled_motion.expect("a moving sled");
        assert_eq!(motion.direction, MotionDirection::Slope);
        cond.motion.direction = Some(MotionDirection::Launch);
        let motion = space.scenario_at(&cond, &x).effects.sled_motion.expect("a moving sled");
        assert_eq!(motion.direction, MotionDirection::Launch);
        assert_eq!(space.names().len(), space.shared.len() + 2, "the direction is not searched");
        // a space may assume a direction for the conditions that state none; a stated one wins
        let launch = space.with_motion_direction(MotionDirection::Launch);
        let mut unstated = cond.clone();
        unstated.motion.direction = None;
        assert!(Space::direction_unstated(&[cond.clone(), unstated.clone()]));
        assert!(!Space::direction_unstated(std::slice::from_ref(&cond)));
        let motion = launch.scenario_at(&unstated, &x).effects.sled_motion.expect("a moving sled");
        assert_eq!(motion.direction, MotionDirection::Launch);
        cond.motion.direction = Some(MotionDirection::Slope);
        let motion = launch.scenario_at(&cond, &x).effects.sled_motion.expect("a moving sled");
        assert_eq!(motion.direction, MotionDirection::Slope);
    }

    /// A varying parameter takes its shared value at the conditions' mean of the variable
    /// and moves by its slope elsewhere; the slope is the space's last dimension.
    #[test]
    fn a_varying_parameter_differs_between_conditions_by_its_slope() {
        use crate::calibrate::varying::{Covariate, Varying};
        let (mut slow, mut fast) = (test3(), test3());
        slow.design.v0 = 1.0;
        fast.design.v0 = 1.4;
        let conds = vec![slow.clone(), fast.clone()];
        let plain = Space::new(shared_params(&conds), &[], &conds);
        let v = Varying::new(Param::KElastic, Covariate::V0, &conds).unwrap();
        let space = plain.with_varying(vec![v]).unwrap();
        assert_eq!(space.dim(), plain.dim() + 1);
        assert_eq!(space.names().last(), Some(&"k_elastic_slope_v0_m_s"));
        let (lo, hi) = *space.bounds().last().unwrap();
        assert!((hi - 0.99 / 0.4).abs() < 1e-12 && lo == -hi, "{lo}..{hi}");
        let x = [0.6, 0.2, 5.0, 0.5];
        assert!((space.scenario_at(&slow, &x).collision.k_elastic - 0.5).abs() < 1e-12);
        assert!((space.scenario_at(&fast, &x).collision.k_elastic - 0.7).abs() < 1e-12);
        assert_eq!(space.scenario_at(&fast, &x).collision.mu_friction, 0.2);
        // a start from the shared fit: its values, the slope 0
        assert_eq!(space.start_from(&plain.names(), &x[..3]), Some(vec![0.6, 0.2, 5.0, 0.0]));
        // only a fitted parameter may vary, once
        let mu_only = Space::new(vec![Param::MuFric], &[], &conds);
        assert!(mu_only.with_varying(vec![v]).unwrap_err().contains("k_elastic is not fitted here"));
        assert!(plain.with_varying(vec![v, v]).unwrap_err().contains("varies more than once"));
    }
}
