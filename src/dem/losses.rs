//! Where the grains the DEM deleted went. LIGGGHTS deletes a grain that leaves the box
//! (`thermo_modify lost ignore`) and says only how many; the held-out lunar designs lost 9–36 %
//! of their grains that way, credited nothing, and whether that is physics (grains going back
//! down the conveyor, past its end) or numerics (grains passing through the mesh) decides
//! whether the DEM's d_avg can be trusted. So the deck dumps every grain's position and
//! velocity at every rest check ([`TRACK`], every 0.02 s of simulated time, settling
//! included) and the step the stroke began ([`STROKE_START`]); a deleted grain is placed by
//! its last sighting, in the mesh's frame at that moment:
//! - **while settling**: deleted before the stroke began (the fill spilled);
//! - **behind the first tooth**: back down the conveyor, off the mesh's low end;
//! - **past the last tooth**: off the mesh's far end;
//! - **through the mesh**: last seen below the mesh's surface — the contact failed to hold
//!   it, a numerical failure, not physics;
//! - **over the top**: above the mesh on a path that leaves through the box's top;
//! - **unplaced**: never seen, or seen where none of the above fits.

use std::io::BufRead;
use std::path::Path;

use anyhow::{bail, Context as _};
use serde::{Deserialize, Serialize};

use super::case::Case;
pub use super::case::{STROKE_START, TRACK};
use super::stl::profile_polyline;
use crate::io::bounded::{open_bounded, read_text_if_present};
use crate::model::geometry::V2;
use crate::schema;

/// Counts of the deleted grains by where they left; they add up to the run's `left_box`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct LeftBy {
    pub while_settling: usize,
    pub behind_first_tooth: usize,
    pub past_last_tooth: usize,
    pub through_mesh: usize,
    pub over_top: usize,
    pub unplaced: usize,
}

impl LeftBy {
    /// Each count with the words a report gives it, in the order above.
    fn parts(&self) -> [(&'static str, usize); 6] {
        [
            ("while settling", self.while_settling),
            ("behind tooth 1", self.behind_first_tooth),
            ("past the last tooth", self.past_last_tooth),
            ("through the mesh", self.through_mesh),
            ("over the top", self.over_top),
            ("unplaced", self.unplaced),
        ]
    }

    pub fn total(&self) -> usize {
        self.parts().iter().map(|(_, n)| n).sum()
    }

    /// The counts of several runs added up; None when any run has none (it wrote no track).
    pub fn summed(runs: impl IntoIterator<Item = Option<LeftBy>>) -> Option<LeftBy> {
        runs.into_iter().try_fold(LeftBy::default(), |a, b| {
            b.map(|b| LeftBy {
                while_settling: a.while_settling + b.while_settling,
                behind_first_tooth: a.behind_first_tooth + b.behind_first_tooth,
                past_last_tooth: a.past_last_tooth + b.past_last_tooth,
                through_mesh: a.through_mesh + b.through_mesh,
                over_top: a.over_top + b.over_top,
                unplaced: a.unplaced + b.unplaced,
            })
        })
    }

    /// The non-zero counts, `name n` joined by commas ("none" when nothing left).
    pub fn describe(&self) -> String {
        let parts: Vec<String> =
            self.parts().iter().filter(|(_, n)| *n > 0).map(|(name, n)| format!("{n} {name}")).collect();
        if parts.is_empty() {
            "none".into()
        } else {
            parts.join(", ")
        }
    }
}

/// One grain's sighting in the track.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seen {
    pub step: u64,
    pub pos: [f64; 2],
    pub vel: [f64; 2],
}

/// The last sighting of each grain (index = id − 1) in a LIGGGHTS `dump custom` of `id x y
/// vx vy` with any number of snapshots, read line by line (a long run's track is large).
pub fn last_seen(reader: impl BufRead, grains: usize) -> anyhow::Result<Vec<Option<Seen>>> {
    let mut seen = vec![None; grains];
    let mut step: Option<u64> = None;
    let mut cols: Option<[usize; 5]> = None;
    let mut expect_step = false;
    for (n, line) in reader.lines().enumerate() {
        let line = line.with_context(|| format!("track line {}", n + 1))?;
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        if let Some(item) = line.strip_prefix("ITEM: ") {
            expect_step = item == "TIMESTEP";
            cols = match item.strip_prefix("ATOMS") {
                Some(names) => {
                    let names: Vec<&str> = names.split_whitespace().collect();
                    let at = |c: &str| {
                        names
                            .iter()
                            .position(|x| *x == c)
                            .with_context(|| format!("track line {}: no column `{c}`", n + 1))
                    };
                    Some([at("id")?, at("x")?, at("y")?, at("vx")?, at("vy")?])
                }
                None => None,
            };
            continue;
        }
        if expect_step {
            step = Some(line.parse().with_context(|| format!("track line {}: `{line}` is not a step", n + 1))?);
            expect_step = false;
            continue;
        }
        let Some(c) = cols else { continue };
        let Some(step) = step else { bail!("track line {}: atoms before any `ITEM: TIMESTEP`", n + 1) };
        let f: Vec<&str> = line.split_whitespace().collect();
        let num = |i: usize| -> anyhow::Result<f64> {
            f.get(i)
                .and_then(|s| s.parse::<f64>().ok())
                .filter(|v| v.is_finite())
                .with_context(|| format!("track line {}: field {} is not a finite number", n + 1, i + 1))
        };
        let id = f
            .get(c[0])
            .and_then(|s| s.parse::<usize>().ok())
            .filter(|id| (1..=grains).contains(id))
            .with_context(|| format!("track line {}: the id is not one of the {grains} grains placed", n + 1))?;
        seen[id - 1] = Some(Seen { step, pos: [num(c[1])?, num(c[2])?], vel: [num(c[3])?, num(c[4])?] });
    }
    Ok(seen)
}

/// Where each of the `deleted` grains (index = id − 1) left, from its last sighting.
pub fn classify(case: &Case, stroke_start_step: u64, seen: &[Option<Seen>], deleted: &[bool]) -> LeftBy {
    let line = profile_polyline(&case.profile(), case.teeth);
    let (x_lo, x_hi) = line.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p[0]), b.max(p[0])));
    let radius = 0.5 * case.largest_diameter_m();
    let g = case.scenario.environment.g;
    let mut out = LeftBy::default();
    for (s, _) in seen.iter().zip(deleted).filter(|(_, d)| **d) {
        let Some(s) = s else {
            out.unplaced += 1;
            continue;
        };
        if s.step < stroke_start_step {
            out.while_settling += 1;
            continue;
        }
        let t = (s.step - stroke_start_step) as f64 * case.contact.timestep_s;
        let shift = case.motion.displacement(t);
        let (x, y) = (s.pos[0] - shift[0], s.pos[1] - shift[1]);
        if x < x_lo {
            out.behind_first_tooth += 1;
        } else if x > x_hi {
            out.past_last_tooth += 1;
        } else if lowest_surface(&line, x).is_some_and(|y_s| y < y_s - radius) {
            out.through_mesh += 1;
        } else if leaves_through_top(case, s, g) {
            out.over_top += 1;
        } else {
            out.unplaced += 1;
        }
    }
    out
}

/// Where each of the `deleted` grains of a steady (periodic) conveyor left, from its last
/// sighting in the conveyor's frame (x along it, wrapped into the period; y normal to it).
/// The conveyor is periodic along x and the slab along z, so a grain leaves only through the
/// box's bottom, under the mesh (`through_mesh`), or its top (`over_top`): below the mesh's
/// surface, or heading down in the box's lower half, is the first; heading up in its upper
/// half the second; anything else (a grain the stroke's push turned between sightings) stays
/// `unplaced`. `settled[i]`: grain i + 1 was on the conveyor after settling (the others left
/// `while_settling`).
pub fn classify_on_conveyor(
    line: &[V2],
    radius: f64,
    box_y: [f64; 2],
    seen: &[Option<Seen>],
    settled: &[bool],
    deleted: &[bool],
) -> LeftBy {
    let mut out = LeftBy::default();
    let middle = 0.5 * (box_y[0] + box_y[1]);
    for ((s, settled), _) in seen.iter().zip(settled).zip(deleted).filter(|(_, d)| **d) {
        if !settled {
            out.while_settling += 1;
            continue;
        }
        let Some(s) = s else {
            out.unplaced += 1;
            continue;
        };
        let (y, vy) = (s.pos[1], s.vel[1]);
        if lowest_surface(line, s.pos[0]).is_some_and(|y_s| y < y_s - radius) || (vy < 0.0 && y < middle) {
            out.through_mesh += 1;
        } else if vy > 0.0 && y >= middle {
            out.over_top += 1;
        } else {
            out.unplaced += 1;
        }
    }
    out
}

/// The lowest height at which the mesh's profile crosses the vertical through `x` (an
/// overhanging tooth crosses it more than once), if it does.
fn lowest_surface(line: &[V2], x: f64) -> Option<f64> {
    line.windows(2)
        .filter(|w| (w[0][0] - x) * (w[1][0] - x) <= 0.0 && w[0][0] != w[1][0])
        .map(|w| w[0][1] + (w[1][1] - w[0][1]) * (x - w[0][0]) / (w[1][0] - w[0][0]))
        .reduce(f64::min)
}

/// Whether a free flight from the sighting (gravity only) leaves the box through its top
/// before any other face.
fn leaves_through_top(case: &Case, s: &Seen, g: f64) -> bool {
    let [[x0, x1], [_, y1], _] = case.bounds;
    let (vx, vy) = (s.vel[0], s.vel[1]);
    // time to the top: y + vy t - g t²/2 = y1 needs vy² ≥ 2 g (y1 − y)
    let rise = vy * vy - 2.0 * g * (y1 - s.pos[1]);
    if vy <= 0.0 || rise < 0.0 {
        return s.pos[1] > y1;
    }
    let t_top = if g > 0.0 { (vy - rise.sqrt()) / g } else { (y1 - s.pos[1]) / vy };
    let t_side = if vx > 0.0 {
        (x1 - s.pos[0]) / vx
    } else if vx < 0.0 {
        (x0 - s.pos[0]) / vx
    } else {
        f64::INFINITY
    };
    t_top <= t_side
}

/// The deleted grains of a finished run placed from its track (a tracked case whose every
/// grain left before the track's first snapshot has none: all unplaced), or None when the case
/// writes no track ([`Case::tracked`]). `deleted[i]`: grain i + 1 is not in the final dump.
pub fn read_losses(case: &Case, dir: &Path, deleted: &[bool]) -> anyhow::Result<Option<LeftBy>> {
    let track_path = dir.join(TRACK);
    if !track_path.is_file() {
        // a tracked case whose every grain left before the first snapshot wrote none
        let unplaced = deleted.iter().filter(|d| **d).count();
        return Ok(case.tracked().then_some(LeftBy { unplaced, ..LeftBy::default() }));
    }
    // no stroke start: every grain left while settling (the deck stopped before the stroke)
    let start_path = dir.join(STROKE_START);
    let start = match read_text_if_present(&start_path, &schema::DEM_STROKE_START_FILE)? {
        Some(t) => t
            .trim()
            .parse::<u64>()
            .map_err(|_| anyhow::anyhow!("{}: `{}` is not a step", start_path.display(), t.trim()))?,
        None => u64::MAX,
    };
    let seen = read_sightings(dir, deleted.len())?;
    Ok(Some(classify(case, start, &seen, deleted)))
}

/// The last sighting of each of `grains` grains in the run folder `dir`'s track ([`TRACK`],
/// read under its bound), or none of them where the run wrote no track file (every grain left
/// before its first snapshot).
pub fn read_sightings(dir: &Path, grains: usize) -> anyhow::Result<Vec<Option<Seen>>> {
    let path = dir.join(TRACK);
    if !path.is_file() {
        return Ok(vec![None; grains]);
    }
    let reader = std::io::BufReader::new(open_bounded(&path, &schema::DEM_TRACK_FILE)?);
    last_seen(reader, grains).with_context(|| format!("reading {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn case() -> Case {
        crate::dem::case::rig_case(40, 8, 1)
    }

    const TRACK_TEXT: &str =
        "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS ff ff pp\n-1 1\n-1 1\n0 0.01\n\
        ITEM: ATOMS id x y vx vy\n1 0.1 0.2 0 0\n2 0.3 0.4 0 0\n\
        ITEM: TIMESTEP\n500\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS ff ff pp\n-1 1\n-1 1\n0 0.01\n\
        ITEM: ATOMS id x y vx vy\n2 0.35 0.45 1.5 -2.5\n";

    #[test]
    fn the_last_sighting_of_each_grain_is_kept() {
        let seen = last_seen(TRACK_TEXT.as_bytes(), 3).unwrap();
        assert_eq!(seen[0], Some(Seen { step: 0, pos: [0.1, 0.2], vel: [0.0, 0.0] }));
        assert_eq!(seen[1], Some(Seen { step: 500, pos: [0.35, 0.45], vel: [1.5, -2.5] }));
        assert_eq!(seen[2], None);
        // a grain the case did not place, a position that is not a number
        let e = last_seen(TRACK_TEXT.as_bytes(), 1).unwrap_err();
        assert!(format!("{e:#}").contains("not one of the 1 grains"), "{e:#}");
        let bad = TRACK_TEXT.replace("0.35 0.45", "nan 0.45");
        assert!(format!("{:#}", last_seen(bad.as_bytes(), 3).unwrap_err()).contains("not a finite number"));
        let no_y = TRACK_TEXT.replace("id x y vx vy", "id x vx vy");
        assert!(format!("{:#}", last_seen(no_y.as_bytes(), 3).unwrap_err()).contains("no column `y`"));
    }

    #[test]
    fn a_deleted_grain_is_placed_by_where_it_was_last_seen() {
        let c = case();
        let line = profile_polyline(&c.profile(), c.teeth);
        let x_lo = line.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min);
        let x_hi = line.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max);
        let mid = 0.5 * (x_lo + x_hi);
        let surface = lowest_surface(&line, mid).unwrap();
        let top = c.bounds[1][1];
        let s0 = 1000;
        // after the stroke has ended the mesh is where the motion leaves it
        let late = s0 + (10.0 / c.contact.timestep_s) as u64;
        let home = c.motion.displacement(f64::INFINITY);
        let at = |x: f64, y: f64, v: [f64; 2]| Some(Seen { step: late, pos: [x + home[0], y + home[1]], vel: v });
        let seen = vec![
            Some(Seen { step: s0 - 1, pos: [mid, surface + 0.01], vel: [0.0, 0.0] }), // before the stroke
            at(x_lo - 0.01, surface, [-0.1, -0.5]),                                   // off the low end
            at(x_hi + 0.01, surface, [0.1, -0.5]),                                    // off the far end
            at(mid, surface - 0.01, [0.0, -0.3]),                                     // under the surface
            at(mid, top - 0.01, [0.0, 2.0]),                                          // rising through the top
            at(mid, surface + 0.02, [0.0, -0.1]),                                     // above the mesh, falling
            None,                                                                     // never seen
            at(mid, surface + 0.02, [0.0, 0.0]),                                      // still in the box
        ];
        let deleted = [true, true, true, true, true, true, true, false];
        let by = classify(&c, s0, &seen, &deleted);
        assert_eq!(
            by,
            LeftBy {
                while_settling: 1,
                behind_first_tooth: 1,
                past_last_tooth: 1,
                through_mesh: 1,
                over_top: 1,
                unplaced: 2,
            }
        );
        assert_eq!(by.total(), 7);
        assert_eq!(
            by.describe(),
            "1 while settling, 1 behind tooth 1, 1 past the last tooth, 1 through the mesh, 1 over the top, 2 unplaced"
        );
        assert_eq!(LeftBy::default().describe(), "none");
        let twice = LeftBy::summed([Some(by), Some(by)]).unwrap();
        assert_eq!((twice.total(), twice.unplaced), (14, 4));
        assert_eq!(LeftBy::summed([Some(by), None]), None);
    }

    /// A periodic conveyor's grains leave through the box's bottom (under the mesh) or its
    /// top, nowhere else: placed by where they were last seen and which way they moved.
    #[test]
    fn a_conveyors_lost_grains_left_through_the_bottom_or_the_top() {
        // one flat tooth at y = 0 over x in [0, 0.1], the box from -0.05 to 0.45
        let line = [[0.0, 0.0], [0.1, 0.0]];
        let at = |x: f64, y: f64, vy: f64| Some(Seen { step: 10, pos: [x, y], vel: [0.0, vy] });
        let seen = [
            at(0.05, -0.01, 0.5), // below the surface, whatever its heading: through the mesh
            at(0.05, 0.01, -2.0), // just above it, heading down: through the mesh
            at(0.05, 0.40, 1.0),  // high and rising: over the top
            at(0.05, 0.40, -1.0), // high and falling: it cannot have left: unplaced
            None,                 // never seen
            at(0.05, 0.30, 0.5),  // lost while settling (not in the settled dump)
            at(0.05, 0.10, 0.0),  // still there
        ];
        let settled = [true, true, true, true, true, false, true];
        let deleted = [true, true, true, true, true, true, false];
        let by = classify_on_conveyor(&line, 0.002, [-0.05, 0.45], &seen, &settled, &deleted);
        assert_eq!(
            by,
            LeftBy { while_settling: 1, through_mesh: 2, over_top: 1, unplaced: 2, ..LeftBy::default() },
            "{}",
            by.describe()
        );
        assert_eq!((by.behind_first_tooth, by.past_last_tooth), (0, 0), "a periodic conveyor has no ends");
    }

    #[test]
    fn the_deck_tracks_every_grain_and_records_when_the_stroke_began() {
        let c = case();
        assert!(c.tracked());
        let script = c.files().unwrap().script;
        let dump = script.lines().position(|l| l.starts_with("dump track all custom ")).expect("a track");
        assert!(script.lines().nth(dump).unwrap().ends_with(&format!("{TRACK} id x y vx vy")));
        // defined before settling, so a grain the fill spills is placed too
        let settle = script.lines().position(|l| l == "label settling").unwrap();
        assert!(dump < settle);
        let start = script.lines().position(|l| l.contains(&format!("file {STROKE_START}"))).expect("the start step");
        let s0 = script.lines().position(|l| l.starts_with("variable s0 equal ${now}")).unwrap();
        let stroke = script.lines().position(|l| l == "# the stroke").unwrap();
        assert!(s0 < start && start < stroke, "{script}");
        // a case whose track would outgrow its bound writes none
        let mut big = c.clone();
        big.settings.max_time_s = 1000.0;
        big.placement.grains = vec![big.placement.grains[0]; 200_000];
        assert!(!big.tracked());
        assert!(!big.files().unwrap().script.contains("dump track"));
    }
}
