//! `--help` is documentation a new user reads first: every command ends with examples that
//! run as written, the scenario flags state their defaults (read from the presets), and the
//! effects are listed in full from the one registry.

use std::process::Command;

use sawtooth::model::effects::EffectKind;
use sawtooth::model::Scenario;

fn help(args: &[&str]) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_sawtooth")).args(args).arg("--help").output().unwrap();
    assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8(o.stdout).unwrap()
}

#[test]
fn every_command_ends_with_examples_of_itself() {
    let commands: &[&[&str]] = &[
        &["simulate"],
        &["bench"],
        &["conformance"],
        &["optimize"],
        &["fit"],
        &["gpu-sweep"],
        &["study"],
        &["campaign"],
        &["synth"],
        &["diagnose"],
        &["dem"],
    ];
    for c in commands {
        let text = help(c);
        let examples = &text[text.find("Example").unwrap_or_else(|| panic!("{c:?} has no examples:\n{text}"))..];
        let name = c[0];
        assert!(examples.contains(&format!("sawtooth {name} ")), "{c:?}: {examples}");
    }
}

#[test]
fn scenario_flags_state_their_defaults_from_the_presets() {
    for c in ["simulate", "optimize", "gpu-sweep"] {
        let text = help(&[c]);
        for flag in
            ["--env", "--alpha", "--k-elastic", "--mu-fric", "--k-drag", "--aor", "--particles", "--teeth", "--seed"]
        {
            let at = text.find(&format!("      {flag} ")).unwrap_or_else(|| panic!("{c}: no {flag}"));
            let entry = &text[at..at + text[at..].find("\n\n").unwrap_or(text.len() - at)];
            assert!(entry.contains("[default: "), "{c} {flag} states no default: {entry}");
        }
        // the numbers are the presets' own
        let (lunar, earth) = (Scenario::lunar(), Scenario::earth());
        assert!(text.contains(&format!("else {}]", lunar.collision.k_elastic)), "{text}");
        assert!(text.contains(&format!("{} 1/s with --env earth", earth.environment.k_drag.unwrap())), "{text}");
        assert!(text.contains(&format!("{} deg with --env lunar", lunar.material.aor_deg)), "{text}");
    }
}

#[test]
fn every_effect_is_listed_with_its_parameters() {
    for c in [&["simulate"][..], &["optimize"], &["synth"], &["study", "repeatability"]] {
        let text = help(c);
        for e in EffectKind::ALL {
            assert!(text.contains(&e.cli_form()), "{c:?} does not list {}", e.cli_form());
        }
    }
    let diagnose = help(&["diagnose"]);
    for e in EffectKind::ALL {
        assert!(diagnose.contains(e.name()), "diagnose --effects does not name {}", e.name());
    }
}
