//! A measured condition from a data CSV (`--data`) and its setup TOML (`--setup`): what
//! `fit` and `diagnose` both read, checked before anything is simulated. Errors name the
//! two files' fields as the user spelled them ([`Spelling`]).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _};

use super::fields::Spelling;
use super::{objective, Condition, KnownMotion, Normalise};
use crate::io::config::ConfigFile;
use crate::io::measured;

/// The file's stem, the condition's short name in reports.
pub fn stem(p: &Path) -> String {
    p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| p.display().to_string())
}

/// The conditions' short names in reports: each data file's stem; where several files share
/// a stem (every DEM campaign's CSV is `dem.csv`), each of those is named by its folder
/// (`earth-deep-slow`), which is what the user chose to tell them apart; a name still
/// taken gets `#` and the condition's number (`dem#2`).
pub fn condition_names(data: &[PathBuf]) -> Vec<String> {
    let stems: Vec<String> = data.iter().map(|p| stem(p)).collect();
    let shared = |s: &String| stems.iter().filter(|t| *t == s).count() > 1;
    let folder = |p: &PathBuf| {
        let p = std::path::absolute(p).unwrap_or_else(|_| p.clone());
        p.parent().and_then(|d| d.file_name()).map(|n| n.to_string_lossy().into_owned())
    };
    let mut names: Vec<String> = Vec::with_capacity(data.len());
    for (i, (p, s)) in data.iter().zip(&stems).enumerate() {
        let mut name = if shared(s) { folder(p).unwrap_or_else(|| s.clone()) } else { s.clone() };
        if names.contains(&name) {
            name = format!("{name}#{}", i + 1);
        }
        names.push(name);
    }
    names
}

/// Load `data` measured with `setup`. The seed of the setup (`sim.seed`) is used where
/// `seed` is None. `normalise` None chooses fractions of the loaded mass where every run
/// records input_mass, else of the recovered mass (D.4).
pub fn load(
    data: &Path,
    setup: &Path,
    name: String,
    normalise: Option<Normalise>,
    seed: Option<u64>,
    spelling: Spelling,
) -> anyhow::Result<Condition> {
    let (data_field, setup_field) = (spelling.name("data"), spelling.name("setup"));
    let runs = measured::load(data).with_context(|| format!("{data_field} {}", data.display()))?;
    let config = ConfigFile::load(setup).with_context(|| format!("{setup_field} {}", setup.display()))?;
    let Some(design) = config.design() else {
        bail!("{setup_field} {}: no [design] table (the rig's sawtooth design is required)", setup.display());
    };
    let mut scenario = config.scenario().with_context(|| format!("{setup_field} {}", setup.display()))?;
    scenario.sim.seed = seed.unwrap_or(scenario.sim.seed);
    if let Err(e) = scenario.validate() {
        bail!("{setup_field} {}: invalid setting: {e}", setup.display());
    }
    if runs.teeth > scenario.sim.teeth as usize {
        bail!(
            "{data_field} {} has {} teeth but the setup simulates only {} (sim.teeth): raise sim.teeth in {}",
            data.display(),
            runs.teeth,
            scenario.sim.teeth,
            setup.display()
        );
    }
    if runs.runs.iter().any(|r| r.recovered_g() <= 0.0) {
        bail!("{data_field} {}: every run needs a positive recovered mass", data.display());
    }
    if let Err(invalid) = crate::model::prepare(&scenario, &design) {
        bail!("{setup_field} {}: the design cannot be simulated ({}): {invalid}", setup.display(), invalid.rule());
    }
    let measurement = config.measurement.as_ref();
    let resolution_g = measurement
        .and_then(|m| m.scale_resolution_g)
        .unwrap_or_else(|| objective::infer_resolution(runs.runs.iter().flat_map(|r| r.teeth_g.iter().copied())));
    let normalise = match normalise {
        Some(Normalise::Loaded) if !Condition::has_input_mass(&runs) => {
            bail!("{} loaded: {data_field} {} lacks input_mass in some run", spelling.name("normalise"), data.display())
        }
        Some(n) => n,
        None if Condition::has_input_mass(&runs) => Normalise::Loaded,
        None => Normalise::Recovered,
    };
    Ok(Condition {
        name,
        data: data.display().to_string(),
        setup: setup.display().to_string(),
        runs,
        base: scenario,
        design,
        resolution_g,
        motion: KnownMotion {
            delay_s: measurement.and_then(|m| m.motion_delay_s),
            return_speed_m_s: measurement.and_then(|m| m.motion_return_speed_m_s),
            direction: measurement.and_then(|m| m.motion_direction),
        },
        motion_profile: measurement.and_then(|m| m.motion_profile.clone()),
        normalise,
        handling_loss_max: measurement.and_then(|m| m.handling_loss_max).unwrap_or(1.0),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn names(paths: &[&str]) -> Vec<String> {
        condition_names(&paths.iter().map(PathBuf::from).collect::<Vec<_>>())
    }

    #[test]
    fn conditions_are_named_by_their_files_stem_while_it_tells_them_apart() {
        let practice = ["data/practice_campaigns/campaign_1/c1.csv", "data/practice_campaigns/campaign_1/c2.csv"];
        assert_eq!(names(&practice), ["c1", "c2"]);
        assert_eq!(names(&["runs/slow.csv", "other/fast.csv", "x/dem.csv"]), ["slow", "fast", "dem"]);
    }

    /// Every DEM campaign's CSV is `dem.csv`: the campaigns' folders name the conditions
    /// (not `dem`, `dem#2`, `dem#3`), and a stem shared with no other keeps its name.
    #[test]
    fn files_that_share_a_stem_are_named_by_their_folders() {
        let dem = ["data/dem/earth-deep-slow/dem.csv", "data/dem/earth-deep-fast/dem.csv", "runs/shallow.csv"];
        assert_eq!(names(&dem), ["earth-deep-slow", "earth-deep-fast", "shallow"]);
        // a bare file name is named by the folder it is read from (the working directory)
        let here = std::env::current_dir().unwrap().file_name().unwrap().to_string_lossy().into_owned();
        assert_eq!(names(&["dem.csv", "a/dem.csv"]), [here, "a".to_string()]);
    }

    /// The same file twice, or two folders of the same name: numbered, as before.
    #[test]
    fn names_still_shared_are_numbered() {
        assert_eq!(names(&["x/dem.csv", "x/dem.csv", "y/dem.csv"]), ["x", "x#2", "y"]);
        assert_eq!(names(&["a/x/dem.csv", "b/x/dem.csv"]), ["x", "x#2"]);
    }
}
