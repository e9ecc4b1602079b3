//! The corrected model as an input (issue 43, 3): the setup's config with the fitted
//! parameters in place of its own, written as a config TOML that every command reads as any
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
    let mut table: toml::Table = toml::from_str(setup_text).context("the setup is not a TOML table")?;
    for (&p, &v) in params.iter().zip(values) {
        anyhow::ensure!(v.is_finite(), "the fitted {} is {v}, not a number to write", p.name());
        let (section, name) = p.config_key();
        let entry = table.entry(section).or_insert_with(|| toml::Value::Table(toml::Table::new()));
        let toml::Value::Table(t) = entry else {
            anyhow::bail!("the setup's `{section}` is not a table");
        };
        t.insert(name.to_string(), toml::Value::Float(v));
    }
    let mut text = String::from(
        "# The corrected model: the setup's config with the parameters fitted by `sawtooth fit`\n\
         # (docs/calibrate-and-diagnose.md). Read it as any config: `--config corrected.toml`.\n",
    );
    for line in provenance {
        text.push_str(&format!("# {line}\n"));
    }
    for (j, (&p, &v)) in params.iter().zip(values).enumerate() {
        let (section, name) = p.config_key();
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
}
