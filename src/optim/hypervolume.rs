//! Exact hypervolume (dominated area) of a 2-D point set, for minimisation.

/// Area dominated by `points` and bounded by `reference` (both objectives minimised).
///
/// Points that do not strictly dominate the reference (or are not finite) contribute nothing
/// and are ignored. Sort by the first objective and sweep: each point that lowers the best
/// second objective seen so far adds the rectangle between it, the previous level and the
/// reference's first coordinate. O(n log n); dominated points and duplicates add zero.
pub fn hypervolume_2d(points: &[[f64; 2]], reference: [f64; 2]) -> f64 {
    let [r0, r1] = reference;
    let mut pts: Vec<[f64; 2]> =
        points.iter().copied().filter(|p| p[0].is_finite() && p[1].is_finite() && p[0] < r0 && p[1] < r1).collect();
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let mut area = 0.0;
    let mut level = r1;
    for [x, y] in pts {
        if y < level {
            area += (r0 - x) * (level - y);
            level = y;
        }
    }
    area
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_set_has_zero_volume() {
        assert_eq!(hypervolume_2d(&[], [1.0, 1.0]), 0.0);
    }

    #[test]
    fn single_point_is_a_rectangle() {
        assert!((hypervolume_2d(&[[0.25, 0.5]], [1.0, 1.0]) - 0.375).abs() < 1e-15);
    }

    #[test]
    fn staircase_of_two_points() {
        // Reference (2,2): (0,1) dominates a 2x1 strip, (1,0) adds the 1x1 square below it.
        let hv = hypervolume_2d(&[[1.0, 0.0], [0.0, 1.0]], [2.0, 2.0]);
        assert!((hv - 3.0).abs() < 1e-15);
    }

    #[test]
    fn dominated_duplicate_and_outside_points_add_nothing() {
        let base = hypervolume_2d(&[[1.0, 0.0], [0.0, 1.0]], [2.0, 2.0]);
        let with_extra = hypervolume_2d(
            &[
                [1.0, 0.0],
                [0.0, 1.0],
                [1.5, 1.5],  // dominated
                [0.0, 1.0],  // duplicate
                [3.0, -1.0], // beyond the reference in x
                [-1.0, 2.0], // on the reference in y: does not dominate it
                [f64::NAN, 0.0],
            ],
            [2.0, 2.0],
        );
        assert_eq!(base, with_extra);
    }

    #[test]
    fn order_does_not_matter() {
        let pts = [[0.1, 0.9], [0.5, 0.5], [0.9, 0.1], [0.3, 0.7]];
        let mut rev = pts;
        rev.reverse();
        assert_eq!(hypervolume_2d(&pts, [1.0, 1.0]), hypervolume_2d(&rev, [1.0, 1.0]));
    }

    #[test]
    fn dense_linear_front_approaches_the_triangle() {
        // Front f2 = 1 - f1 on [0,1], reference (1,1): exact area of the region below is 1/2.
        let n = 100_000;
        let pts: Vec<[f64; 2]> = (0..=n)
            .map(|i| {
                let t = i as f64 / n as f64;
                [t, 1.0 - t]
            })
            .collect();
        let hv = hypervolume_2d(&pts, [1.0, 1.0]);
        assert!((hv - 0.5).abs() < 1e-4, "hv = {hv}");
        assert!(hv < 0.5, "a sampled front never exceeds the continuous one");
    }
}
