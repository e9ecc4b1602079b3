//! Single grains in LIGGGHTS, beside the model's restitution law (issue 42): one grain of a
//! case's size, density and contact (the same moduli, COR, Coulomb and rolling friction, time
//! step and contact model as the case, `super::contact`) hits a flat mesh of the case's wall
//! at a given speed and angle from the normal, with no gravity; its rebound gives the DEM's
//! normal COR v_n'/v_n, tangential ratio v_t'/v_t and spin ω r / v_t. Beside it the model's
//! law (`Restitution::bounce`, Eq. 4.47-4.49, with the scenario's `[collision] law`).
//!
//! It is how a user checks any mapping of contacts, and how the DEM's law is measured for the
//! model ([`measure_law`]: k_t at the nodes ψ of `TANGENTIAL_PSI`, `ContactLaw::Dem`).
//!
//! Each impact is its own LIGGGHTS run in `DIR/impact-NNN/` (a fraction of a second each).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use anyhow::{bail, Context as _};
use serde::Serialize;

use super::case::{Case, DUMP, SCRIPT};
use super::contact::{property_commands, CONTACT_MODEL};
use super::gather::parse_dump;
use super::run::run_case;
use super::stl::{extrude, facet_line, stl_text};
use crate::io::atomic::write_atomic;
use crate::model::collision::{Restitution, TANGENTIAL_NODES, TANGENTIAL_PSI};
use crate::model::{Collision, ContactLaw};

const PLATE: &str = "plate.stl";
const GRAIN: &str = "grain.data";
/// The grain starts this fraction of its radius above the plate.
const GAP_RADII: f64 = 0.01;
/// Contact durations the run lasts after the grain reaches the plate.
const CONTACT_DURATIONS: f64 = 8.0;
/// ψ at which the table's first node (ψ = 0, no tangential speed: k_t undefined) is measured:
/// below ψ ≈ 0.05 a single impact at the case's step keeps its tiny tangential speed, above
/// it the tangential spring reverses it, and the first table interval stands for the latter.
const PSI_AT_ZERO: f64 = 0.1;

/// One impact: what went in and what came out, in the DEM and in the model.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Impact {
    pub speed_m_s: f64,
    /// Angle of the impact velocity from the surface normal, degrees (0: head-on).
    pub angle_deg: f64,
    /// |v_t| / (μ (1 + k_elastic) |v_n|): the tangential speed over the most Coulomb friction
    /// takes from it (`TANGENTIAL_PSI`); infinite without friction.
    pub psi: f64,
    pub dem_normal_cor: f64,
    /// v_t'/v_t (None head-on).
    pub dem_tangential_ratio: Option<f64>,
    /// ω r / v_t after the impact (None head-on): the spin the model does not carry.
    pub dem_spin_ratio: Option<f64>,
    pub model_normal_cor: f64,
    pub model_tangential_ratio: Option<f64>,
}

/// Normal and tangential components of an impact of `speed` at `angle_deg` from the normal.
fn components(speed: f64, angle_deg: f64) -> (f64, f64) {
    let a = angle_deg.to_radians();
    (speed * a.cos(), speed * a.sin())
}

/// The files of one impact of `case`'s grain (its smallest class) at normal speed `vn` and
/// tangential speed `vt`: script, grain data, plate mesh.
fn impact_files(case: &Case, vn: f64, vt: f64) -> (String, String, String) {
    let c = &case.contact;
    let d = case.placement.classes.iter().map(|k| k.diameter_m).fold(f64::INFINITY, f64::min);
    let r = d / 2.0;
    let depth = 4.0 * d;
    // how long: the gap, then the contact a few times over (Hertz duration at vn)
    let m = c.density_kg_m3 * std::f64::consts::PI * d.powi(3) / 6.0;
    let e_star =
        1.0 / ((1.0 - c.grain_poisson.powi(2)) / c.grain_youngs_pa + (1.0 - c.wall_poisson.powi(2)) / c.wall_youngs_pa);
    let t_contact = 2.87 * (m * m / (r * e_star * e_star * vn.max(1e-3))).powf(0.2);
    let t_end = GAP_RADII * r / vn.max(1e-3) + CONTACT_DURATIONS * t_contact;
    let travel = vt * t_end + 4.0 * d;
    let (x0, x1) = (-4.0 * d, travel);
    let plate = facet_line(&[[x1, 0.0], [x0, 0.0]], d);
    let stl = stl_text("plate", &extrude(&plate, depth));
    let data = format!(
        "sawtooth dem impact grain\n\n1 atoms\n2 atom types\n\n{:e} {:e} xlo xhi\n{:e} {:e} ylo yhi\n0 {:e} zlo zhi\n\nAtoms\n\n1 1 {:e} {} 0 {:e} {:e}\n\nVelocities\n\n1 {:e} {:e} 0 0 0 0\n",
        x0 - d,
        x1 + d,
        -2.0 * d,
        (vn * t_end).max(d) + 4.0 * d,
        depth,
        d,
        c.density_kg_m3,
        r * (1.0 + GAP_RADII),
        0.5 * depth,
        vt,
        -vn
    );
    let steps = (t_end / c.timestep_s).ceil() as u64;
    let script = format!(
        "# sawtooth dem impact: one grain of the case on its wall (docs/dem.md)\n\
         atom_style granular\natom_modify map array\nboundary f f p\nnewton off\ncommunicate single vel yes\nunits si\n\
         read_data {GRAIN}\nneighbor {:e} bin\nneigh_modify delay 0\n\
         {}fix plate all mesh/surface file {PLATE} type 2\n\
         fix walls all wall/gran {CONTACT_MODEL} mesh n_meshes 1 meshes plate\n\
         fix integrate all nve/sphere\nthermo_modify lost ignore norm no\nrun {steps}\n\
         write_dump all custom {DUMP} id type diameter mass x y z vx vy vz omegax omegay omegaz\n",
        0.5 * d,
        property_commands(c),
    );
    (script, data, stl)
}

/// The rebound (v_n', v_t', ω r) of one impact, run by LIGGGHTS in `dir`.
fn run_impact(case: &Case, binary: &Path, dir: &Path, vn: f64, vt: f64) -> anyhow::Result<(f64, f64, f64)> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let (script, data, stl) = impact_files(case, vn, vt);
    write_atomic(&dir.join(PLATE), stl.as_bytes())?;
    write_atomic(&dir.join(GRAIN), data.as_bytes())?;
    write_atomic(&dir.join(SCRIPT), script.as_bytes())?;
    run_case(binary, dir, &mut |_| {})?;
    let text = crate::io::bounded::read_text(&dir.join(DUMP), &crate::schema::DEM_DUMP_FILE)?;
    let grain = parse_dump(&text)?.into_iter().next().context("the impact's dump holds no grain")?;
    let r = case.placement.classes.iter().map(|k| k.diameter_m).fold(f64::INFINITY, f64::min) / 2.0;
    if grain.pos[1] <= r {
        bail!("the grain is still on the plate at the end of the impact run in {}", dir.display());
    }
    let spin = parse_spin(&text)?;
    Ok((grain.vel[1], grain.vel[0], spin * r))
}

/// The first grain's ω_z from a dump with an `omegaz` column.
fn parse_spin(text: &str) -> anyhow::Result<f64> {
    let mut lines = text.lines();
    let header = lines.by_ref().find(|l| l.starts_with("ITEM: ATOMS")).context("dump has no `ITEM: ATOMS`")?;
    let col = header.split_whitespace().skip(2).position(|c| c == "omegaz").context("dump lacks `omegaz`")?;
    let line = lines.find(|l| !l.trim().is_empty()).context("dump holds no grain")?;
    let v: f64 = line.split_whitespace().nth(col).and_then(|s| s.parse().ok()).context("bad omegaz")?;
    anyhow::ensure!(v.is_finite(), "omegaz is not finite");
    Ok(v)
}

/// Run the impacts `(vn, vt)` of `case` in `dir/impact-NNN/`, up to `jobs` at a time; the
/// rebounds in order.
fn run_all(
    case: &Case,
    binary: &Path,
    dir: &Path,
    list: &[(f64, f64)],
    jobs: usize,
) -> anyhow::Result<Vec<(f64, f64, f64)>> {
    let next = AtomicUsize::new(0);
    // one slot per impact of `list`, filled by whichever worker runs it
    type Slot = Option<anyhow::Result<(f64, f64, f64)>>;
    let out: Mutex<Vec<Slot>> = Mutex::new((0..list.len()).map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..jobs.max(1).min(list.len().max(1)) {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::SeqCst);
                let Some(&(vn, vt)) = list.get(k) else { break };
                let sub: PathBuf = dir.join(format!("impact-{:03}", k + 1));
                let r = run_impact(case, binary, &sub, vn, vt);
                out.lock().expect("no panic holds it")[k] = Some(r);
            });
        }
    });
    out.into_inner().expect("no panic holds it").into_iter().map(|r| r.expect("every impact ran")).collect()
}

/// The model's law at `case`'s scenario: (k_n, k_t) for an impact (vn, vt) on a flat surface.
fn model_ratios(case: &Case, vn: f64, vt: f64) -> (f64, Option<f64>) {
    let s = &case.scenario;
    let law = Restitution::new(s.mode, &s.collision, &s.material);
    let out = law.bounce([vt, -vn], [0.0, 1.0]);
    (out[1] / vn, (vt > 0.0).then(|| out[0] / vt))
}

fn psi_of(case: &Case, vn: f64, vt: f64) -> f64 {
    let c = &case.contact;
    let impulse = c.sliding_friction * (1.0 + c.restitution) * vn;
    if impulse > 0.0 {
        vt / impulse
    } else {
        f64::INFINITY
    }
}

/// Every impact of `speeds` × `angles_deg` (from the normal, in [0, 89]) of `case`'s grain, in
/// `dir`, beside the model's law.
pub fn measure(
    case: &Case,
    binary: &Path,
    dir: &Path,
    speeds: &[f64],
    angles_deg: &[f64],
    jobs: usize,
) -> anyhow::Result<Vec<Impact>> {
    let mut list = Vec::new();
    for &v in speeds {
        for &a in angles_deg {
            list.push((v, a, components(v, a)));
        }
    }
    let pairs: Vec<(f64, f64)> = list.iter().map(|l| l.2).collect();
    let rebounds = run_all(case, binary, dir, &pairs, jobs)?;
    Ok(list
        .iter()
        .zip(rebounds)
        .map(|(&(speed, angle, (vn, vt)), (vn_out, vt_out, spin))| {
            let (model_normal_cor, model_tangential_ratio) = model_ratios(case, vn, vt);
            let tangential = vt > 1e-12 * speed;
            Impact {
                speed_m_s: speed,
                angle_deg: angle,
                psi: psi_of(case, vn, vt),
                dem_normal_cor: vn_out / vn,
                dem_tangential_ratio: tangential.then(|| vt_out / vt),
                dem_spin_ratio: tangential.then(|| spin / vt),
                model_normal_cor,
                model_tangential_ratio: if tangential { model_tangential_ratio } else { None },
            }
        })
        .collect())
}

/// The normal speed the DEM law's table is measured at: the design's launch speed over two
/// (the tangential response depends on ψ, hardly on the speed: `dem impact` shows both).
pub fn law_speed(case: &Case) -> f64 {
    0.5 * case.design.v0
}

/// The DEM's restitution law for `case`'s contact (`ContactLaw::Dem`): k_elastic and μ as the
/// case passes them to LIGGGHTS, and k_t measured at each node ψ of `TANGENTIAL_PSI` (ψ = 0
/// at ψ = 0.1) at the normal speed [`law_speed`], in `dir`.
pub fn measure_law(case: &Case, binary: &Path, dir: &Path, jobs: usize) -> anyhow::Result<Collision> {
    let c = &case.contact;
    let vn = law_speed(case);
    let impulse = c.sliding_friction * (1.0 + c.restitution) * vn;
    let tangential_ratio = if impulse > 0.0 {
        let list: Vec<(f64, f64)> = TANGENTIAL_PSI.iter().map(|&p| (vn, p.max(PSI_AT_ZERO) * impulse)).collect();
        run_all(case, binary, dir, &list, jobs)?
            .iter()
            .zip(&list)
            .map(|((_, vt_out, _), (_, vt))| (vt_out / vt).clamp(-1.0, 1.0))
            .collect()
    } else {
        // no friction: the tangential speed is kept
        vec![1.0; TANGENTIAL_NODES]
    };
    Ok(Collision { law: ContactLaw::Dem, tangential_ratio, ..Collision::thesis(c.restitution, c.sliding_friction) })
}

/// The measured law as a config fragment (`[collision]`), with where it came from.
pub fn law_toml(law: &Collision, case: &Case) -> String {
    let mut t = String::new();
    let _ = writeln!(
        t,
        "# The DEM's restitution law, measured by `sawtooth dem impact` on single grains of the case\n\
         # ({:.0} um, {:.0} kg/m^3, COR {}, mu {}, rolling friction {}, moduli softened x{:.3e}) at a\n\
         # normal speed of {:.3} m/s: k_t at psi = {:?} (psi = |v_t| / (mu (1 + e) |v_n|)).",
        case.placement.classes.iter().map(|k| k.diameter_m).fold(f64::INFINITY, f64::min) * 1e6,
        case.contact.density_kg_m3,
        case.contact.restitution,
        case.contact.sliding_friction,
        case.contact.rolling_friction,
        case.contact.softening,
        law_speed(case),
        TANGENTIAL_PSI
    );
    let ratios: Vec<String> = law.tangential_ratio.iter().map(|v| format!("{v:.4}")).collect();
    let _ = writeln!(
        t,
        "[collision]\nlaw = \"dem\"\nk_elastic = {}\nmu_friction = {}\ntangential_ratio = [{}]",
        law.k_elastic,
        law.mu_friction,
        ratios.join(", ")
    );
    t
}

/// The two laws side by side: the normal COR over the normal speed, and the tangential ratio
/// over ψ, DEM points and the model's law.
pub struct ImpactPlot<'a> {
    impacts: &'a [Impact],
    title: String,
}

const PLOT_SIZE: (u32, u32) = (1000, 520);

impl<'a> ImpactPlot<'a> {
    pub fn new(impacts: &'a [Impact], case: &Case) -> Self {
        let c = &case.contact;
        let title = format!(
            "Single impacts: DEM (LIGGGHTS) vs model ({} law) | COR {}, mu {}, rolling {}, {:.0} um",
            match case.scenario.collision.law {
                ContactLaw::Thesis => "thesis",
                ContactLaw::Dem => "DEM",
            },
            c.restitution,
            c.sliding_friction,
            c.rolling_friction,
            case.placement.classes.iter().map(|k| k.diameter_m).fold(f64::INFINITY, f64::min) * 1e6
        );
        ImpactPlot { impacts, title }
    }

    fn legend() -> [(crate::plot::Mark, &'static str); 2] {
        use crate::plot::{Mark, PALETTE};
        [(Mark::Point(PALETTE[1]), "DEM (single grain in LIGGGHTS)"), (Mark::Diamond(PALETTE[0]), "model's law")]
    }
}

impl crate::plot::Figure for ImpactPlot<'_> {
    fn size(&self) -> (u32, u32) {
        PLOT_SIZE
    }

    fn draw<DB: plotters::prelude::DrawingBackend>(
        &self,
        root: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    ) -> anyhow::Result<()> {
        use crate::plot::{self, Drawn, PALETTE};
        use plotters::prelude::*;
        let area = plot::title(root, &self.title)?;
        let (w, h) = area.dim_in_pixel();
        let legend = Self::legend();
        let (panels, key) = area.split_vertically(h - plot::legend_height(w, &legend));
        let halves = panels.split_evenly((1, 2));
        let normal: Vec<(f64, f64, f64)> = self
            .impacts
            .iter()
            .map(|i| (i.speed_m_s * i.angle_deg.to_radians().cos(), i.dem_normal_cor, i.model_normal_cor))
            .collect();
        let tangential: Vec<(f64, f64, f64)> = self
            .impacts
            .iter()
            .filter(|i| i.psi.is_finite())
            .filter_map(|i| Some((i.psi, i.dem_tangential_ratio?, i.model_tangential_ratio?)))
            .collect();
        type Panel<'a> = (&'a [(f64, f64, f64)], &'a str, &'a str);
        let panels: [Panel; 2] = [
            (&normal, "normal impact speed |v_n| [m/s]", "normal COR v_n'/v_n"),
            (&tangential, "psi = |v_t| / (mu (1+e) |v_n|)", "tangential ratio v_t'/v_t"),
        ];
        for (area, (points, x_desc, y_desc)) in halves.iter().zip(panels) {
            let xs = points.iter().map(|p| p.0);
            let ys = points.iter().flat_map(|p| [p.1, p.2]);
            let (x0, x1) = plot::extent(xs).unwrap_or((0.0, 1.0));
            let (y0, y1) = plot::extent(ys).unwrap_or((0.0, 1.0));
            let mut chart = ChartBuilder::on(area)
                .margin(15)
                .x_label_area_size(50)
                .y_label_area_size(60)
                .build_cartesian_2d(plot::padded(x0, x1, 0.05), plot::padded(y0.min(0.0), y1.max(1.0), 0.05))
                .drawn()?;
            plot::draw_numeric_axes(&mut chart, x_desc, y_desc)?;
            chart
                .draw_series(points.iter().map(|p| {
                    EmptyElement::at((p.0, p.2))
                        + Polygon::new(vec![(0, -5), (5, 0), (0, 5), (-5, 0)], PALETTE[0].filled())
                }))
                .drawn()?;
            chart.draw_series(points.iter().map(|p| Circle::new((p.0, p.1), 4, PALETTE[1].filled()))).drawn()?;
        }
        plot::legend(&key, &legend)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rig_case() -> Case {
        crate::dem::case::rig_case(60, 6, 0)
    }

    #[test]
    fn an_impact_starts_just_above_the_plate_with_the_asked_velocity_and_the_cases_contact() {
        let case = rig_case();
        let (script, data, stl) = impact_files(&case, 0.5, 0.2);
        assert!(script.contains(&property_commands(&case.contact)), "{script}");
        assert!(script.contains("fix walls all wall/gran model hertz tangential history rolling_friction cdt"));
        assert!(!script.contains("gravity"), "no gravity in a single impact");
        let d = case.placement.diameter_m;
        assert!(data.contains("\n1 2e-1 -5e-1 0 0 0 0\n"), "{data}");
        let atom = data.lines().find(|l| l.starts_with("1 1 ")).unwrap();
        let y: f64 = atom.split_whitespace().nth(5).unwrap().parse().unwrap();
        assert!((y - 0.5 * d * (1.0 + GAP_RADII)).abs() < 1e-12, "{atom}");
        // the plate is flat at y = 0 and reaches past the grain's travel
        let v = crate::dem::stl::parse_vertices(&stl);
        assert!(v.iter().all(|p| p[1] == 0.0));
        assert!(v.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max) > 4.0 * d);
    }

    #[test]
    fn the_models_ratios_follow_its_configured_law() {
        let mut case = rig_case();
        let (kn, kt) = model_ratios(&case, 0.001, 0.01);
        assert!((kn - case.scenario.collision.k_elastic).abs() < 1e-12, "below v_limit: k_elastic");
        assert!(kt.unwrap() > 0.0);
        case.scenario.collision = Collision {
            law: ContactLaw::Dem,
            tangential_ratio: vec![0.5; TANGENTIAL_NODES],
            ..case.scenario.collision.clone()
        };
        let (kn, kt) = model_ratios(&case, 1.5, 0.01);
        assert!((kn - case.scenario.collision.k_elastic).abs() < 1e-12, "the DEM law keeps one COR");
        assert!((kt.unwrap() - 0.5).abs() < 1e-12);
    }
}
