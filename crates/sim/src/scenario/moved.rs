//! Files in an old form: the planner form, a `[planner]` table of flat keys (and the closed loop's
//! `cna.standoff_radius_m`) where the planners and baselines now have their own `[policy.NAME]`
//! tables; the CNA form, where `cna.gps_sd` and the AUV CNA's `nav_diffusion`, `surfacing` and
//! `broadcasts_truth` stated its navigation, now one model, `cna.navigation`. Such a file is
//! refused with one message that lists every moved key it sets and the new place of each, so one
//! edit moves them all.

use crate::scenario::file::ScenarioError;
use std::path::Path;

/// The keys of one old form and what replaced them.
pub struct Moved {
    /// What changed, as the message says it.
    pub headline: &'static str,
    /// Each old key and its new place (a key's inline-table leaves go with it).
    pub keys: &'static [(&'static str, &'static str)],
}

/// Where each key of a closed-loop scenario's old planner form now sits. Where the old key served
/// several policies, each instance now has its own.
pub const SIMULATE: Moved = Moved {
    headline: "the old planner form: every planner and baseline now has its own [policy.NAME] table",
    keys: &[
        ("planner.heading_options", "policy.planner.tree.heading_options (and policy.open-loop.tree.heading_options)"),
        ("planner.look_ahead", "policy.planner.tree.look_ahead (and policy.open-loop.tree.look_ahead)"),
        ("planner.penalty_case", "policy.planner.penalty = { case = \"...\" } (each planner instance has its own)"),
        ("planner.error", "policy.planner.cost = { kind = \"hudson\", alpha, bearing, terms }"),
        ("planner.limits", "policy.planner.limits (each planner instance has its own)"),
        ("planner.deadline", "policy.planner.deadline (each planner instance has its own)"),
        ("planner.parallel", "policy.planner.search.parallel (each planner instance has its own)"),
        ("planner.start_after_reports", "policy.start_after_reports"),
        ("planner.before_first_report", "policy.before_first_report"),
        ("planner.thesis_waypoints", "policy.predictor.waypoints (true: { at_most = 3 }, or min(L, 3))"),
        ("planner.model_lost_pings", "policy.planner.cost.model_lost_pings"),
        ("planner.link", "policy.link"),
        ("planner.sigma0", "policy.planner.cost.sigma0"),
        ("planner.eps0", "policy.planner.cost.eps0"),
        ("planner.predictor", "policy.predictor"),
        ("planner.horizon", "policy.planner-estimator.horizon"),
        ("planner.estimator_tracking", "policy.planner-estimator.cost.tracking"),
        ("planner.estimator_aggregate", "policy.planner-estimator.cost.aggregate"),
        ("planner.estimator_bias_per_km", "policy.planner-estimator.cost.bias_per_km"),
        ("planner.estimator_bias_profile", "policy.planner-estimator.cost.bias_profile"),
        ("planner.estimator_level_off", "policy.planner-estimator.tree.level_off"),
        ("planner.estimator_slot_reach", "policy.planner-estimator.cost.slot_reach"),
        ("planner.estimator_terminal_levels", "policy.planner-estimator.cost.terminal_levels"),
        ("planner.estimator_unmodelled_current", "policy.planner-estimator.cost.unmodelled_current"),
        ("planner.estimator_drift_levels", "policy.planner-estimator.cost.drift_levels"),
        ("planner.estimator_reach_success", "policy.planner-estimator.cost.reach_success"),
        ("planner.estimator_penalty_case", "policy.planner-estimator.penalty = { case = \"...\" }"),
        ("planner.estimator_look_ahead", "policy.planner-estimator.tree.look_ahead"),
        ("planner.estimator_heading_options", "policy.planner-estimator.tree.heading_options"),
        ("planner.estimator_pitch_levels", "policy.planner-estimator.tree.pitch_levels"),
        ("planner.estimator_cna_variance", "policy.planner-estimator.cost.cna_variance"),
        ("planner.estimator_truth", "policy.planner-estimator.cost.truth"),
        ("planner.estimator_current", "policy.planner-estimator.cost.current"),
        ("cna.standoff_radius_m", "policy.centroid-standoff.radius_m"),
    ],
};

/// Where each key of a scenario's old CNA form now sits: its navigation is `cna.navigation`, one
/// model apart from the vehicle (`cna.auv`).
pub const CNA_NAVIGATION: Moved = Moved {
    headline: "the old CNA form: the CNA's navigation is one model, cna.navigation, apart from the vehicle (cna.auv)",
    keys: &[
        ("cna.gps_sd", "cna.navigation = { kind = \"gps\", sd_m }"),
        ("cna.auv.nav_diffusion", "cna.navigation = { kind = \"dead-reckoning\", diffusion_m2_s }"),
        ("cna.auv.surfacing", "cna.navigation.surfacing"),
        ("cna.auv.broadcasts_truth", "cna.navigation = { kind = \"exact\", diffusion_m2_s, surfacing }"),
    ],
};

/// Where each key of a pre-deployment scenario's old `[planner]` table now sits.
pub const PLAN: Moved = Moved {
    headline: "the old planner form: every planner and baseline now has its own [policy.NAME] table",
    keys: &[
        ("planner.look_ahead", "policy.planner.tree.look_ahead"),
        ("planner.penalty", "policy.planner.penalty"),
        ("planner.motion.heading_options", "policy.planner.tree.heading_options"),
        ("planner.motion.speed", "platform.speed"),
        ("planner.motion.tau", "platform.tau"),
        ("planner.motion.max_turn_rate_deg_s", "platform.max_turn_rate_deg_s"),
        ("planner.motion.cna", "platform.cna"),
        ("planner.error.alpha", "policy.planner.cost.alpha (cost = { kind = \"hudson\", ... })"),
        ("planner.error.bearing", "policy.planner.cost.bearing"),
        ("planner.error.cost", "policy.planner.cost.terms"),
        ("planner.limits", "policy.planner.limits"),
        ("planner.search.deadline", "policy.planner.deadline"),
        ("planner.search", "policy.planner.search"),
    ],
};

/// Every leaf key path of `value` under `path` (an empty table is a leaf).
fn leaves(path: &str, value: &toml::Value, out: &mut Vec<String>) {
    match value {
        toml::Value::Table(t) if !t.is_empty() => {
            for (k, v) in t {
                leaves(&format!("{path}.{k}"), v, out);
            }
        }
        _ => out.push(path.to_string()),
    }
}

/// The moved keys `text` sets, each with its new place, in `moved`'s order (a key of an old
/// `[planner]` table no longer known is listed as such); empty when the file is not in the old
/// form. Text that is not TOML is left to the parser.
pub fn moved_keys(text: &str, moved: &[(&str, &str)]) -> Vec<(String, String)> {
    let Ok(table) = text.parse::<toml::Table>() else { return Vec::new() };
    let planner_form = moved.iter().any(|(old, _)| old.starts_with("planner."));
    let mut found = Vec::new();
    for (old, _) in moved {
        let mut parts = old.split('.');
        let top = parts.next().unwrap_or_default();
        let mut at = table.get(top);
        for part in parts {
            at = at.and_then(|v| v.get(part));
        }
        if let Some(v) = at {
            leaves(old, v, &mut found);
        }
    }
    let mut out: Vec<(String, String)> = Vec::new();
    for leaf in &found {
        let (old, new) = moved
            .iter()
            .filter(|(old, _)| leaf == old || leaf.starts_with(&format!("{old}.")))
            .max_by_key(|(old, _)| old.len())
            .expect("every leaf was found under a moved key");
        if !out.iter().any(|(o, _)| o == old) {
            out.push((old.to_string(), new.to_string()));
        }
    }
    if let Some(planner) = table.get("planner").and_then(toml::Value::as_table).filter(|_| planner_form) {
        let mut unknown: Vec<String> = Vec::new();
        if !planner.is_empty() {
            leaves("planner", &toml::Value::Table(planner.clone()), &mut unknown);
        }
        for leaf in unknown {
            let known = moved.iter().any(|(old, _)| leaf == *old || leaf.starts_with(&format!("{old}.")));
            if !known {
                out.push((leaf, "no such key: see the [policy.NAME] tables (scenarios/README.md)".into()));
            }
        }
        if out.is_empty() {
            out.push(("planner".into(), "[policy.planner] (and [policy.planner-estimator])".into()));
        }
    }
    out
}

/// Refuses `text` when it is in any of the old `forms`, with every moved key and its new place in
/// one message.
pub fn refuse_old_form(text: &str, file: &Path, forms: &[&Moved]) -> Result<(), ScenarioError> {
    let mut headlines = Vec::new();
    let mut keys = Vec::new();
    for form in forms {
        let found = moved_keys(text, form.keys);
        if !found.is_empty() && !headlines.contains(&form.headline) {
            headlines.push(form.headline);
        }
        keys.extend(found);
    }
    if keys.is_empty() {
        return Ok(());
    }
    let list: String = keys.iter().map(|(old, new)| format!("\n  {old} -> {new}")).collect();
    Err(ScenarioError::Parse {
        file: file.to_path_buf(),
        message: format!("{}; {} moved key(s), each with its new place:{list}", headlines.join("; "), keys.len()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file with several old keys, inline tables among them, gets every one listed once with
    /// its new place, in one message; a file in the new form passes.
    #[test]
    fn every_moved_key_is_listed_with_its_new_place() {
        let old = "seed = 1\n[cna]\nx = 0.0\nstandoff_radius_m = 150.0\n[planner]\nlook_ahead = 5\n\
                   limits = { min = 100.0, max = 1000.0 }\nestimator_look_ahead = 4\n\
                   estimator_truth = { drift_m2_s = 0.002, range_noise = { sigma_m = 1.8 } }\nlink = \"assumed\"\n\
                   surprise = 3\n";
        let e = refuse_old_form(old, Path::new("old.toml"), &[&SIMULATE, &CNA_NAVIGATION]).unwrap_err().to_string();
        let lines = [
            "planner.look_ahead -> policy.planner.tree.look_ahead (and policy.open-loop.tree.look_ahead)",
            "planner.limits -> policy.planner.limits (each planner instance has its own)",
            "planner.link -> policy.link",
            "planner.estimator_truth -> policy.planner-estimator.cost.truth",
            "planner.estimator_look_ahead -> policy.planner-estimator.tree.look_ahead",
            "cna.standoff_radius_m -> policy.centroid-standoff.radius_m",
            "planner.surprise -> no such key",
        ];
        for line in lines {
            assert!(e.contains(&format!("\n  {line}")), "{line} missing from: {e}");
        }
        assert!(e.starts_with("scenario old.toml: the old planner form") && e.contains("7 moved key(s)"), "{e}");
        assert_eq!(e.matches("\n  planner.limits ->").count(), 1, "an inline table's leaves are one key: {e}");
        let new = "seed = 1\n[policy.planner]\ncost = { kind = \"hudson\" }\n";
        refuse_old_form(new, Path::new("new.toml"), &[&SIMULATE, &CNA_NAVIGATION]).unwrap();
        let empty = refuse_old_form("[planner]\n", Path::new("e.toml"), &[&SIMULATE]).unwrap_err().to_string();
        assert!(empty.contains("planner -> [policy.planner]"), "{empty}");
    }

    /// A file in both old forms gets both headlines and every key of each in one message; the
    /// CNA form's keys are no `[planner]` keys, so they are not listed as unknown ones.
    #[test]
    fn keys_of_both_old_forms_come_in_one_message() {
        let old = "[cna]\ngps_sd = 1.0\nauv = { pitch_options = 1, depth = 10.0, nav_diffusion = 0.01 }\n\
                   [planner]\nlink = \"assumed\"\n";
        let e = refuse_old_form(old, Path::new("both.toml"), &[&SIMULATE, &CNA_NAVIGATION]).unwrap_err().to_string();
        assert!(e.starts_with("scenario both.toml: the old planner form") && e.contains("; the old CNA form"), "{e}");
        for line in [
            "planner.link -> policy.link",
            "cna.gps_sd -> cna.navigation = { kind = \"gps\", sd_m }",
            "cna.auv.nav_diffusion -> cna.navigation = { kind = \"dead-reckoning\", diffusion_m2_s }",
        ] {
            assert!(e.contains(&format!("\n  {line}")), "{line} missing from: {e}");
        }
        assert!(e.contains("3 moved key(s)") && !e.contains("no such key"), "{e}");
        let cna_only = refuse_old_form("[cna]\ngps_sd = 2.0\n", Path::new("c.toml"), &[&SIMULATE, &CNA_NAVIGATION]);
        let e = cna_only.unwrap_err().to_string();
        assert!(e.starts_with("scenario c.toml: the old CNA form") && e.contains("1 moved key(s)"), "{e}");
    }

    #[test]
    fn a_pre_deployment_files_motion_keys_go_to_the_platform() {
        let old = "[planner]\nlook_ahead = 4\npenalty = { case = \"8\" }\n[planner.motion]\nspeed = 3.0\ntau = 10.0\n\
                   heading_options = 5\ncna = { kind = \"asc\" }\n[planner.error]\nalpha = 0.1\n\
                   [planner.search]\ndeadline = { kind = \"none\" }\nparallel = true\n";
        let e = refuse_old_form(old, Path::new("p.toml"), &[&PLAN]).unwrap_err().to_string();
        for line in [
            "planner.look_ahead -> policy.planner.tree.look_ahead",
            "planner.penalty -> policy.planner.penalty",
            "planner.motion.speed -> platform.speed",
            "planner.motion.tau -> platform.tau",
            "planner.motion.heading_options -> policy.planner.tree.heading_options",
            "planner.motion.cna -> platform.cna",
            "planner.error.alpha -> policy.planner.cost.alpha",
            "planner.search.deadline -> policy.planner.deadline",
            "planner.search -> policy.planner.search",
        ] {
            assert!(e.contains(&format!("\n  {line}")), "{line} missing from: {e}");
        }
        assert!(e.contains("9 moved key(s)"), "{e}");
    }
}
