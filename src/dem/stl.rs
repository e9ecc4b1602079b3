//! The sled's tooth profile as a triangle mesh: the model's own polyline (p1 → p2 up the
//! ramp, the catch arc from p2 down to p4, the base on to the next p1; Eq. 4.21-4.28,
//! `model::geometry::Profile`) extruded over the periodic depth.
//!
//! Facets are kept short: LIGGGHTS 3.8's mesh neighbour build (`SurfaceMesh`'s topology
//! pass over a `RegionNeighborList` binned at 4 × the largest facet's bounding radius) stops
//! with an assertion (region_neighbor_list_I.h:165: a facet centre's 27-bin stencil leaves
//! the bins) when facets are much longer than the thin periodic depth; which facet and why
//! was not traced further. Measured on the rig's 600-grain case (2 mm facets): depths of 1.25 mm and more pass,
//! 1.10 mm and less stop (issue 31 at 2 mm facets, issue 42 at 600 grains). Every segment is
//! therefore cut into pieces no longer than the smaller of 2 mm and the depth
//! (`facet_line`).

use std::fmt::Write as _;

use crate::model::geometry::{Profile, V2};

/// Longest facet edge along the profile on a deep slab, m (issue 31: ≤ ~2 mm passed
/// LIGGGHTS's check).
pub const MAX_FACET_M: f64 = 2e-3;

/// `line` cut into the facets of a slab `depth_m` deep: every mesh writer's one way to its
/// facets, so that none can forget the thin slab's rule ([`facet_length_m`]).
pub fn facet_line(line: &[V2], depth_m: f64) -> Vec<V2> {
    subdivide(line, facet_length_m(depth_m))
}

/// Longest facet edge along the profile for a slab `depth_m` deep: 2 mm, and never longer
/// than the depth (a thin slab's long facets trip LIGGGHTS's mesh binning, module note).
fn facet_length_m(depth_m: f64) -> f64 {
    MAX_FACET_M.min(depth_m)
}

/// Points per radian of the catch arc before subdivision (a 60° arc gets 12 chords).
const ARC_POINTS_PER_RAD: f64 = 12.0;

/// The profile's surface line from tooth 0's p1 to the last tooth's p4 (where the model's
/// base ends in the physical mode, `Prepared::base_length`), global coordinates.
pub fn profile_polyline(profile: &Profile, teeth: u32) -> Vec<V2> {
    let (a2, a4) = profile.catch_arc_angles();
    let arc_steps = (((a4 - a2) * ARC_POINTS_PER_RAD).ceil() as usize).max(4);
    let mut line = Vec::new();
    for j in 0..teeth {
        let p1 = profile.p1_of(j);
        line.push(p1);
        line.push(profile.point_of(j, profile.p2));
        let c = profile.point_of(j, profile.p3);
        for k in 1..arc_steps {
            let ang = a2 + (a4 - a2) * k as f64 / arc_steps as f64;
            line.push([c[0] + profile.radius * ang.cos(), c[1] + profile.radius * ang.sin()]);
        }
        line.push(profile.point_of(j, profile.p4));
    }
    line
}

/// `line` with every segment cut into equal pieces no longer than `max_len`.
fn subdivide(line: &[V2], max_len: f64) -> Vec<V2> {
    let mut out = Vec::with_capacity(line.len() * 4);
    for w in line.windows(2) {
        let (a, b) = (w[0], w[1]);
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        let n = ((len / max_len).ceil() as usize).max(1);
        for k in 0..n {
            let f = k as f64 / n as f64;
            out.push([a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]);
        }
    }
    if let Some(last) = line.last() {
        out.push(*last);
    }
    // a zero-length segment (p4 on the next p1, ω = 90° designs) would make a degenerate facet
    out.dedup_by(|b, a| (b[0] - a[0]).hypot(b[1] - a[1]) < 1e-12);
    out
}

pub type Triangle = [[f64; 3]; 3];

/// Two triangles per segment of `line`, spanning z = 0..depth, wound so that the normal
/// points into the air (left of the direction of travel along the profile, +y on the base).
pub fn extrude(line: &[V2], depth: f64) -> Vec<Triangle> {
    let mut tris = Vec::with_capacity(2 * line.len());
    for w in line.windows(2) {
        let (a, b) = (w[0], w[1]);
        let a0 = [a[0], a[1], 0.0];
        let b0 = [b[0], b[1], 0.0];
        let a1 = [a[0], a[1], depth];
        let b1 = [b[0], b[1], depth];
        tris.push([a0, a1, b0]);
        tris.push([b0, a1, b1]);
    }
    tris
}

fn normal(t: &Triangle) -> [f64; 3] {
    let u = [t[1][0] - t[0][0], t[1][1] - t[0][1], t[1][2] - t[0][2]];
    let v = [t[2][0] - t[0][0], t[2][1] - t[0][1], t[2][2] - t[0][2]];
    let n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    [n[0] / l, n[1] / l, n[2] / l]
}

/// ASCII STL text of `tris`, coordinates in metres (LIGGGHTS `units si`).
pub fn stl_text(name: &str, tris: &[Triangle]) -> String {
    let mut s = String::with_capacity(tris.len() * 260);
    let _ = writeln!(s, "solid {name}");
    for t in tris {
        let n = normal(t);
        let _ = writeln!(s, "facet normal {:e} {:e} {:e}\n outer loop", n[0], n[1], n[2]);
        for v in t {
            let _ = writeln!(s, "  vertex {:.9e} {:.9e} {:.9e}", v[0], v[1], v[2]);
        }
        let _ = writeln!(s, " endloop\nendfacet");
    }
    let _ = writeln!(s, "endsolid {name}");
    s
}

/// Read back the (x, y) of every vertex of an ASCII STL (for checks against the model).
pub fn parse_vertices(text: &str) -> Vec<[f64; 3]> {
    text.lines()
        .filter_map(|l| l.trim().strip_prefix("vertex "))
        .filter_map(|rest| {
            let v: Vec<f64> = rest.split_whitespace().filter_map(|x| x.parse().ok()).collect();
            (v.len() == 3).then(|| [v[0], v[1], v[2]])
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::geometry::check_design;
    use crate::model::Design;

    fn rig(alpha: f64) -> Profile {
        let d = Design::validation_rig();
        Profile::new(&d, check_design(&d).unwrap(), alpha, 5)
    }

    #[test]
    fn the_polyline_passes_through_every_teeths_p1_p2_and_p4() {
        let p = rig(35.0);
        let line = profile_polyline(&p, 5);
        let near = |q: V2| line.iter().any(|v| (v[0] - q[0]).hypot(v[1] - q[1]) < 1e-12);
        for j in 0..5 {
            assert!(near(p.p1_of(j)), "p1 of tooth {j}");
            assert!(near(p.point_of(j, p.p2)), "p2 of tooth {j}");
            assert!(near(p.point_of(j, p.p4)), "p4 of tooth {j}");
        }
        // the arc points lie on the catch circle
        let c = p.p3;
        let on_circle = line.iter().filter(|v| ((v[0] - c[0]).hypot(v[1] - c[1]) - p.radius).abs() < 1e-12).count();
        assert!(on_circle >= 5, "{on_circle}");
    }

    #[test]
    fn facets_are_never_longer_than_a_thin_slab_is_deep() {
        assert_eq!(facet_length_m(5e-3), MAX_FACET_M);
        assert_eq!(facet_length_m(1e-3), 1e-3);
        let line = facet_line(&profile_polyline(&rig(35.0), 5), 0.7e-3);
        assert!(line.windows(2).all(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]) <= 0.7e-3 + 1e-12));
    }

    #[test]
    fn facets_are_short_and_face_the_air() {
        let p = rig(20.0);
        let line = subdivide(&profile_polyline(&p, 5), MAX_FACET_M);
        for w in line.windows(2) {
            assert!((w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]) <= MAX_FACET_M + 1e-12);
        }
        let tris = extrude(&line, 1.2e-3);
        assert_eq!(tris.len(), 2 * (line.len() - 1));
        // the first segment is tooth 0's ramp: its normal is the model's ramp normal
        let [_, ramp, _] = p.normals();
        let n = normal(&tris[0]);
        assert!((n[0] - ramp[0]).abs() < 1e-9 && (n[1] - ramp[1]).abs() < 1e-9, "{n:?} vs {ramp:?}");
        let back = parse_vertices(&stl_text("sled", &tris));
        assert_eq!(back.len(), 3 * tris.len());
        assert!((back[0][0] - tris[0][0][0]).abs() < 1e-12);
    }
}
