//! The sub-cell grid against the exact polyhedral overlap on 2000 random pairs — boxes of
//! random aspect ratio and twelve-point convex hulls at random orientations and depths, thin
//! wedges and slivers among them whose edges and tapering corners lie between any grid lines:
//! no overlap is missed, and where both surfaces are polyhedra the grid's cells are clipped by
//! their faces, so volume and contact point are exact at every `N_c` (the grid forced with
//! `with_polyhedra_on_grid`: by default such pairs take the exact clipping itself).

#[path = "common/polyhedra.rs"]
mod polyhedra;

use discrete_contact::compute_overlap;
use discrete_contact::prelude::*;

/// Median and worst of the magnitudes.
fn spread(mut e: Vec<f64>) -> (f64, f64) {
    e.iter_mut().for_each(|x| *x = x.abs());
    e.sort_by(f64::total_cmp);
    (e[e.len() / 2], e[e.len() - 1])
}

/// First touches at `N_c = 2`, 8 and 16 and, for `N_c = 8`, the persistent contact seeded
/// with the first touch's box (its grid puts node layers on faces): volume, contact point,
/// surface area and normal equal the exact clipping's to round-off.
#[test]
fn the_grid_finds_every_polyhedral_overlap_exactly() {
    let mut rng = polyhedra::Rng(0x9E37_79B9_7F4A_7C15);
    let cases = 2000;
    let settings =
        |n| OverlapSettings::new(n, IntegrationMode::Subcell).unwrap().with_polyhedra_on_grid(true);
    let (s2, s8, s16) = (settings(2), settings(8), settings(16));
    let (mut volume, mut point, mut area, mut normal) = (vec![], vec![], vec![], vec![]);
    for k in 0..cases {
        let case = polyhedra::case(&mut rng, k);
        let eval = |s: &OverlapSettings, previous: Option<&parry3d_f64::bounding_volume::Aabb>| {
            compute_overlap(&case.a, &case.pose_a, &case.b, &case.pose_b, s, previous)
                .unwrap()
                .unwrap_or_else(|| {
                    panic!("case {k}: an overlap of {:.3e} m³ reported apart", case.exact.volume)
                })
        };
        let g8 = eval(&s8, None);
        for g in [eval(&s2, None), eval(&s8, Some(&g8.corrected_box)), eval(&s16, None), g8] {
            let (ev, ec) = polyhedra::errors(&case, &g);
            volume.push(ev);
            point.push(ec);
            let (ea, en) = polyhedra::facet_errors(&case, &g);
            area.push(ea);
            normal.push(en);
        }
    }
    let ((vm, vw), (pm, pw)) = (spread(volume), spread(point));
    let ((am, aw), (nm, nw)) = (spread(area), spread(normal));
    println!("volume error median {vm:.2e} worst {vw:.2e}, point {pm:.2e} / {pw:.2e}");
    println!("surface area error median {am:.2e} worst {aw:.2e}, normal {nm:.2e} / {nw:.2e} rad");
    assert!(vw <= 1e-9 && pw <= 1e-9, "volume error worst {vw:e}, contact point {pw:e}");
    assert!(aw <= 1e-9 && nw <= 1e-9, "surface area error worst {aw:e}, normal {nw:e} rad");
}

/// By default a sub-cell evaluation of two polyhedra is the exact clipping itself, with the
/// footprint of its faces: the same volume, point and normal as the grid, and a footprint
/// whose area is the mean of the two bodies' surface areas and whose centroid lies within the
/// overlap's reach of its centroid.
#[test]
fn polyhedral_pairs_take_the_exact_clipping_by_default() {
    let mut rng = polyhedra::Rng(0x2545_F491_4F6C_DD1D);
    for k in 0..200 {
        let case = polyhedra::case(&mut rng, k);
        let s = OverlapSettings::new(4, IntegrationMode::Subcell).unwrap();
        let g = compute_overlap(&case.a, &case.pose_a, &case.b, &case.pose_b, &s, None)
            .unwrap()
            .expect("overlapping");
        let grid = compute_overlap(
            &case.a,
            &case.pose_a,
            &case.b,
            &case.pose_b,
            &s.with_polyhedra_on_grid(true),
            None,
        )
        .unwrap()
        .expect("overlapping");
        let (ev, ec) = polyhedra::errors(&case, &g);
        assert!(ev <= 1e-12 && ec <= 1e-12, "case {k}: {ev:e} {ec:e}");
        assert!((g.normal - grid.normal).length() <= 1e-9, "case {k}");
        let f = g.footprint.expect("a footprint");
        assert!((f.area - 0.5 * g.surface_area).abs() <= 1e-12 * g.surface_area, "case {k}");
        // The box is in the pair's frame, the footprint in the world's: compare distances.
        let diagonal = (g.corrected_box.maxs - g.corrected_box.mins).length();
        assert!((f.centroid - g.contact_point).length() <= diagonal, "case {k}");
    }
}
