//! The corrected model as an input (issue 43, 3): the setup's config with the parameters a
//! `fit` or a `diagnose` fitted in place of its own, written as a config TOML that every command reads as any
//! config (`simulate`, `optimize`, `gpu-sweep`, `study`, `dem`, the Python package). Its
//! provenance (the data, the setup, the seed, the fit's quality) and each value's bootstrap
//! sd ride along as comments, which every reader skips.

use anyhow::Context as _;

use crate::calibrate::Param;

/// The file `fit --out DIR` writes.
pub const CORRECTED: &str = "corrected.toml";

/// `setup_text` (a config TOML) with `values` of `params` set, and `provenance` lines and
/// each value's sd (where known) as comments at the top. The result is checked to read back
/// as a config with exactly those values.
pub fn corrected_toml(
    setup_text: &str,
    params: &[Param],
    values: &[f64],
    sd: Option<&[f64]>,
    provenance: &[String],
) -> anyhow::Result<String> {
    let keys: Vec<(&str, &str)> = params.iter().map(|p| p.config_key()).collect();
    corrected_config(setup_text, &keys, values, sd, "sawtooth fit", provenance)
}

/// `setup_text` with each `values[i]` at `keys[i]` (a table's path, dotted for a nested one
/// such as `effects.fill_surface_loss`, and the key), headed by who fitted them (`by`), the
/// `provenance` lines and each value's sd where known; checked to read back as a config. The
/// setup's `[measurement]` and its `[dem]` grain diameter and mesh length (one campaign's,
/// one design's) are left out.
pub fn corrected_config(
    setup_text: &str,
    keys: &[(&str, &str)],
    values: &[f64],
    sd: Option<&[f64]>,
    by: &str,
    provenance: &[String],
) -> anyhow::Result<String> {
    let mut table: toml::Table = toml::from_str(setup_text).context("the setup is not a TOML table")?;
    // what belongs to the one campaign only is left out, so the model reads for any design:
    // its measurement, and the DEM grain size and mesh length of its design
    table.remove("measurement");
    if let Some(toml::Value::Table(dem)) = table.get_mut("dem") {
        dem.remove("grain_diameter_m");
        dem.remove("teeth");
    }
    for (&(section, name), &v) in keys.iter().zip(values) {
        anyhow::ensure!(v.is_finite(), "the fitted [{section}] {name} is {v}, not a number to write");
        let mut t = &mut table;
        for part in section.split('.') {
            let entry = t.entry(part).or_insert_with(|| toml::Value::Table(toml::Table::new()));
            let toml::Value::Table(inner) = entry else {
                anyhow::bail!("the setup's `{part}` is not a table");
            };
            t = inner;
        }
        t.insert(name.to_string(), toml::Value::Float(v));
    }
    let mut text = format!(
        "# The corrected model: the setup's config with the parameters fitted by `{by}`\n\
         # (docs/calibrate-and-diagnose.md). Read it as any config: `--config corrected.toml`.\n"
    );
    for line in provenance {
        text.push_str(&format!("# {line}\n"));
    }
    for (j, (&(section, name), &v)) in keys.iter().zip(values).enumerate() {
        let spread = match sd.and_then(|s| s.get(j)) {
            Some(s) if s.is_finite() => format!(", bootstrap sd {s:.4}"),
            _ => String::new(),
        };
        text.push_str(&format!("# fitted: [{section}] {name} = {v}{spread}\n"));
    }
    text.push('\n');
    text.push_str(&toml::to_string(&table).context("writing the corrected config")?);
    // what was written reads back as a config carrying the fitted values
    crate::io::config::ConfigFile::parse(&text).context("the corrected config does not read back")?;
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fitted_values_replace_the_setups_and_everything_else_stays() {
        let setup = "env = \"earth\"\n[design]\nl_c_mm = 20.0\nl_a_mm = 15.0\nl_b_mm = 5.0\nr_mm = 5.0\nomega_deg = 60.0\n\
                     delta_deg = 0.0\nv0_m_s = 1.4\na_m_s2 = 60.0\n[collision]\nk_elastic = 0.854\nmu_friction = 0.133\n\
                     [environment]\nalpha_deg = 35\nk_drag_per_s = 5.347\n";
        let text = corrected_toml(
            setup,
            &[Param::KElastic, Param::MuFric, Param::KDrag],
            &[0.42, 0.053, 4.5],
            Some(&[0.011, 0.009, 0.2]),
            &["fitted on data.csv".to_string()],
        )
        .unwrap();
        let t: toml::Table = toml::from_str(&text).unwrap();
        assert_eq!(t["collision"]["k_elastic"].as_float(), Some(0.42));
        assert_eq!(t["collision"]["mu_friction"].as_float(), Some(0.053));
        assert_eq!(t["environment"]["k_drag_per_s"].as_float(), Some(4.5));
        assert_eq!(t["environment"]["alpha_deg"].as_integer(), Some(35));
        assert_eq!(t["design"]["l_c_mm"].as_float(), Some(20.0));
        assert_eq!(t["env"].as_str(), Some("earth"));
        assert!(text.contains("# fitted on data.csv\n"), "{text}");
        assert!(text.contains("# fitted: [collision] k_elastic = 0.42, bootstrap sd 0.0110"), "{text}");
        let s = crate::io::config::ConfigFile::parse(&text).unwrap().scenario().unwrap();
        assert_eq!((s.collision.k_elastic, s.collision.mu_friction, s.environment.k_drag), (0.42, 0.053, Some(4.5)));
    }

    #[test]
    fn a_setup_without_the_table_gains_it_and_a_non_number_is_refused() {
        let text = corrected_toml("env = \"lunar\"\n", &[Param::KElastic], &[0.5], None, &[]).unwrap();
        assert!(text.contains("[collision]\nk_elastic = 0.5"), "{text}");
        assert!(corrected_toml("", &[Param::KElastic], &[f64::NAN], None, &[]).is_err());
        let e = corrected_toml("collision = 3\n", &[Param::KElastic], &[0.5], None, &[]).unwrap_err();
        assert!(format!("{e:#}").contains("`collision` is not a table"), "{e:#}");
    }

    /// A diagnosis's effect parameters go to their nested `[effects.KEY]` table, and what
    /// belongs to one campaign (its measurement, its design's DEM grain and mesh) stays out.
    #[test]
    fn effect_parameters_nest_and_the_campaigns_own_keys_stay_out() {
        let setup = "env = \"lunar\"\n[measurement]\nparticle_mass_g = 20.9\n[dem]\nparticles = 150\n\
                     grain_diameter_m = 0.0045\nteeth = 10\n[effects.impact_scatter]\nsigma_deg = 3.0\n";
        let text = corrected_config(
            setup,
            &[
                ("collision", "k_elastic"),
                ("effects.fill_surface_loss", "speed_loss"),
                ("effects.fill_surface_loss", "decay_depth_m"),
            ],
            &[0.57, 0.55, 0.003],
            None,
            "sawtooth diagnose",
            &[],
        )
        .unwrap();
        let t: toml::Table = toml::from_str(&text).unwrap();
        assert_eq!(t["effects"]["fill_surface_loss"]["speed_loss"].as_float(), Some(0.55));
        assert_eq!(t["effects"]["fill_surface_loss"]["decay_depth_m"].as_float(), Some(0.003));
        assert_eq!(t["collision"]["k_elastic"].as_float(), Some(0.57));
        assert!(t.get("measurement").is_none(), "{text}");
        assert_eq!(t["dem"]["particles"].as_integer(), Some(150));
        assert!(t["dem"].get("grain_diameter_m").is_none() && t["dem"].get("teeth").is_none(), "{text}");
        assert!(text.contains("fitted by `sawtooth diagnose`"), "{text}");
        let read = crate::io::config::ConfigFile::parse(&text).unwrap();
        assert!(read.effects.is_some());
    }
}
