//! A campaign plan read back is input like any other (issue 34): a plan.json edited by hand
//! (a member with `"pop": 1000000000`, `particles: 4294967295`, `max_generations: 1e12`, no
//! members at all) is refused naming the member and its field before anything is allocated
//! or run, by the same rules as a new run's settings (`Manifest::validate`, `schema`).

use std::collections::HashSet;

use super::multi::Plan;
use crate::schema::{CHECKPOINT_EVERY, PLAN_MEMBERS};

/// Every rule a plan must meet; the first broken one, naming its field.
pub fn validate_plan(plan: &Plan) -> Result<(), String> {
    PLAN_MEMBERS.check_usize("`members` (their number)", plan.members.len())?;
    CHECKPOINT_EVERY.check("`checkpoint_every`", plan.checkpoint_every)?;
    let mut dirs = HashSet::new();
    for (i, m) in plan.members.iter().enumerate() {
        let at = |e: String| format!("member {i} ({}): {e}", m.label);
        m.manifest.validate().map_err(|e| at(format!("`manifest`: {e}")))?;
        if m.manifest.engine != plan.engine {
            return Err(at(format!(
                "`manifest.engine` {:?} differs from the plan's `engine` {:?}",
                m.manifest.engine, plan.engine
            )));
        }
        if !dirs.insert(m.dir.as_str()) {
            return Err(at(format!("`dir` `{}` is another member's too; each member has its own folder", m.dir)));
        }
    }
    Ok(())
}
