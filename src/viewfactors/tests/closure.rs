//! Closure for open scenes: sky view factors, the matrix conditioned for models that need
//! closure (reciprocity exact, no row above 1, no entry moved beyond the estimate), and
//! entries dropped below a threshold in pairs.

use super::super::matrix::ViewFactors;
use super::super::options::ViewFactorOptions;
use super::Fixture;

fn at(fixture: &Fixture, tolerance: f64, each_direction: bool) -> ViewFactors {
    fixture.view_factors(&ViewFactorOptions { tolerance, each_direction, ..Default::default() })
}

/// The largest |F_ij - G_ij| over both matrices' entries.
fn largest_difference(f: &ViewFactors, g: &ViewFactors) -> f64 {
    f.to_dense().iter().zip(&g.to_dense()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
}

#[test]
fn sky_view_factors_are_one_less_the_row_sums_and_zero_in_a_closed_scene() {
    let open = Fixture::new(crate::scene::city(3, 2).unwrap());
    let f = at(&open, 1e-6, false);
    let sky = f.sky_view_factors();
    let (lo, hi) = f.row_sum_range();
    let (sky_lo, sky_hi) = sky.iter().fold((1.0f64, 0.0f64), |(a, b), &s| (a.min(s), b.max(s)));
    assert_eq!((sky_lo, sky_hi), (1.0 - hi, 1.0 - lo));
    // Roofs see only the sky; the ground and walls see buildings.
    assert!(sky_hi == 1.0 && sky_lo < 0.9, "{sky_lo} {sky_hi}");
    let closed = Fixture::new(crate::scene::cube().unwrap());
    let f = at(&closed, 1e-8, false);
    assert!(f.sky_view_factors().iter().all(|s| s.abs() <= 1e-7), "{:?}", f.sky_view_factors());
}

/// Each direction integrated on its own: conditioning makes reciprocity exact and leaves no
/// row above 1, moving no entry beyond the run's estimate; on closed scenes some rows still
/// exceed 1 by their entries' errors once reciprocity is exact, and are scaled.
#[test]
fn conditioning_makes_reciprocity_exact_and_rows_at_most_one_within_the_estimate() {
    let mut scaled = 0;
    for (fixture, tolerance) in [
        (Fixture::new(crate::scene::city(3, 2).unwrap()), 1e-4),
        (Fixture::new(crate::scene::cube().unwrap()), 1e-6),
        (Fixture::new(crate::scene::generated::room_with_boxes(0)), 1e-4),
        (Fixture::new(crate::scene::baffled_box().unwrap()), 1e-4),
    ] {
        let before = at(&fixture, tolerance, true);
        assert!(before.reciprocity_error() > 1e-12, "{}", before.reciprocity_error());
        let mut f = before.clone();
        let done = f.condition().unwrap();
        assert!(f.reciprocity_error() <= 1e-15, "{}", f.reciprocity_error());
        assert!(f.row_sum_range().1 <= 1.0, "{:?}", f.row_sum_range());
        assert!(f.sky_view_factors().iter().all(|&s| s >= 0.0));
        let moved = largest_difference(&f, &before);
        assert_eq!(moved, done.largest_change);
        assert!(moved > 0.0 && moved <= before.error_estimate, "{moved} {}", before.error_estimate);
        scaled += done.rows_scaled;
    }
    assert!(scaled > 0);
}

/// An estimate that cannot cover the changes: refused, naming the entry, with F unchanged.
#[test]
fn conditioning_beyond_the_estimate_is_refused_naming_the_entry() {
    let fixture = Fixture::new(crate::scene::cube().unwrap());
    let mut f = at(&fixture, 1e-6, true);
    f.error_estimate = 1e-18;
    let before = f.clone();
    let err = f.condition().unwrap_err().to_string();
    assert!(err.contains("F(") && err.contains("tighten --tolerance"), "{err}");
    assert_eq!(f.to_dense(), before.to_dense());
}

/// Pairs with both entries below the threshold go; what stays keeps reciprocity, and the
/// largest row sum dropped is what the rows lost.
#[test]
fn dropping_small_entries_goes_by_pairs_and_says_what_each_row_lost() {
    let fixture = Fixture::new(crate::scene::city(3, 2).unwrap());
    let full = at(&fixture, 1e-6, false);
    let mut f = full.clone();
    for bad in [0.0, -1.0, 1.5, f64::NAN] {
        assert!(f.drop_below(bad).unwrap_err().to_string().contains("drop-below"), "{bad}");
    }
    let dropped = f.drop_below(1e-3).unwrap();
    assert!(dropped.entries > 0 && f.nonzeros() + dropped.entries == full.nonzeros());
    assert!(f.reciprocity_error() <= 1e-15);
    let (n, dense, kept) = (full.len(), full.to_dense(), f.to_dense());
    let mut lost = vec![0.0f64; n];
    for (k, (&a, &b)) in dense.iter().zip(&kept).enumerate() {
        let (i, j) = (k / n, k % n);
        assert!(b == a || (b == 0.0 && a < 1e-3 && dense[j * n + i] < 1e-3), "F({i}, {j})");
        lost[i] += a - b;
    }
    let largest = lost.into_iter().fold(0.0, f64::max);
    assert!((largest - dropped.largest_row_sum).abs() <= 1e-15, "{largest}");
}
