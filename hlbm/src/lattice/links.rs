//! The links of the momentum exchange: for every particle node, which of its 18 links leave
//! its particle (towards a fluid node or another particle, never into a wall). Found before
//! each step through a dense owner field that is updated sparsely, so a step rebuilds the
//! links only of the rows whose neighbourhood changed.

use rayon::prelude::*;

use super::simd::row_links;
use super::{wrap_step, Lattice};
use crate::d3q19::{C, Q};

/// The owner field's mark for a wall node (no body index + 1 reaches it).
pub(super) const WALL_OWNER: u32 = u32::MAX;

/// A neighbouring row `(dy, dz)` and the directions `(dx, i)` that point into it.
type NeighbourRow = (i64, i64, &'static [(i64, usize)]);

/// The nine rows a row's links reach, as `(dy, dz, [(dx, direction)])`: D3Q19's 18 moving
/// directions grouped by the row they point into.
const NEIGHBOUR_ROWS: [NeighbourRow; 9] = {
    const fn dirs(dy: i32, dz: i32) -> [(i64, usize); 3] {
        let mut out = [(0, 0); 3];
        let mut n = 0;
        let mut i = 1;
        while i < Q {
            if C[i][1] == dy && C[i][2] == dz {
                out[n] = (C[i][0] as i64, i);
                n += 1;
            }
            i += 1;
        }
        out
    }
    const R00: [(i64, usize); 3] = dirs(0, 0);
    const RP0: [(i64, usize); 3] = dirs(1, 0);
    const RM0: [(i64, usize); 3] = dirs(-1, 0);
    const R0P: [(i64, usize); 3] = dirs(0, 1);
    const R0M: [(i64, usize); 3] = dirs(0, -1);
    const RPP: [(i64, usize); 3] = dirs(1, 1);
    const RPM: [(i64, usize); 3] = dirs(1, -1);
    const RMP: [(i64, usize); 3] = dirs(-1, 1);
    const RMM: [(i64, usize); 3] = dirs(-1, -1);
    [
        (0, 0, R00.split_at(2).0),
        (1, 0, &RP0),
        (-1, 0, &RM0),
        (0, 1, &R0P),
        (0, -1, &R0M),
        (1, 1, RPP.split_at(1).0),
        (1, -1, RPM.split_at(1).0),
        (-1, 1, RMP.split_at(1).0),
        (-1, -1, RMM.split_at(1).0),
    ]
};

impl Lattice {
    /// Marks, for every particle node, the links that leave its particle: to a node that is
    /// fluid (not a wall) and not covered by the same particle.
    ///
    /// Through a dense owner field (body index + 1 per node, [`WALL_OWNER`] on walls, 0
    /// elsewhere; 4 B per node), updated sparsely slab by slab on all cores: a row whose nodes
    /// (`x` and body) are the last call's is left alone, another has the last call's nodes
    /// cleared and its own set. Then only the rows next to a changed one (or changed
    /// themselves) find their links again: per direction, one pass ([`row_links`]) compares
    /// the owners along the row's span of particle nodes with those of the neighbouring row it
    /// points into. A body moving a small fraction of a cell per step changes few of its rows
    /// in a step, so most rows keep their links. (`hlbm/PERFORMANCE.md` compares this with
    /// the alternatives.)
    pub(super) fn find_links(&mut self) {
        let (nx, ny, nz) = (self.nx, self.ny, self.nz);
        let kind = &self.kind;
        let rows = self.particles.rows();
        let mut owner = std::mem::take(&mut self.owner);
        let mut set = std::mem::take(&mut self.owned);
        let mut changed = std::mem::take(&mut self.changed);
        if owner.len() != kind.len() {
            // (Re)built: every row with nodes differs from the empty list.
            owner = kind.iter().map(|&k| if k != 0 { WALL_OWNER } else { 0 }).collect();
            set.clear();
        }
        set.resize(rows, Vec::new());
        changed.resize(rows, false);
        let particles = &self.particles;
        owner
            .par_chunks_mut(nx * ny)
            .zip(set.par_chunks_mut(ny))
            .zip(changed.par_chunks_mut(ny))
            .enumerate()
            .for_each(|(z, ((slab, rows), changed))| {
                for (y, (row, changed)) in rows.iter_mut().zip(changed.iter_mut()).enumerate() {
                    let nodes = particles.row(z * ny + y);
                    *changed = nodes.len() != row.len()
                        || nodes
                            .iter()
                            .zip(row.iter())
                            .any(|(n, &(x, body))| n.x != x || n.body() as u32 != body);
                    if !*changed {
                        continue;
                    }
                    // A wall node stays a wall (a particle covering one is the caller's error).
                    for &(x, _) in row.iter() {
                        let o = &mut slab[y * nx + x as usize];
                        if *o != WALL_OWNER {
                            *o = 0;
                        }
                    }
                    row.clear();
                    for n in nodes {
                        let o = &mut slab[y * nx + n.x as usize];
                        if *o != WALL_OWNER {
                            *o = n.body() as u32 + 1;
                        }
                        row.push((n.x, n.body() as u32));
                    }
                }
            });
        let mut links = std::mem::take(&mut self.links);
        links.resize(rows, Vec::new());
        // The rows' node positions from the compact list just built (the particle nodes
        // were 64 B apart then: reading them again measured a third of this pass).
        let (xs, changed_ref) = (&set, &changed);
        links.par_chunks_mut(ny).enumerate().for_each(|(z, slab)| {
            let mut span = vec![0u32; nx];
            for (y, masks) in slab.iter_mut().enumerate() {
                let near = |dy: i64, dz: i64| {
                    changed_ref[wrap_step(z, dz, nz) * ny + wrap_step(y, dy, ny)]
                };
                if !(-1..=1).any(|dz| (-1..=1).any(|dy| near(dy, dz))) {
                    continue;
                }
                masks.clear();
                row_links(&owner, &xs[z * ny + y], y, z, [nx, ny, nz], &mut span, masks);
            }
        });
        self.links = links;
        self.owner = owner;
        self.owned = set;
        self.changed = changed;
    }
}

/// [`row_links`] for any instruction set: per direction one pass over the row's whole span of
/// particle nodes, comparing contiguous owners (the first and last node of the row, whose
/// links can wrap round the x face, one by one).
#[inline(always)]
pub(super) fn row_links_generic(
    owner: &[u32],
    nodes: &[(u32, u32)],
    y: usize,
    z: usize,
    dims: [usize; 3],
    span: &mut [u32],
    masks: &mut Vec<u32>,
) {
    let [nx, ny, nz] = dims;
    let (Some(&(first, _)), Some(&(last, _))) = (nodes.first(), nodes.last()) else { return };
    let own = (z * ny + y) * nx;
    let lo = (first as usize).max(1);
    let hi = (last as usize + 1).min(nx - 1).max(lo);
    span[lo..hi].fill(0);
    let mut ends = [0u32; 2];
    for (dy, dz, dirs) in NEIGHBOUR_ROWS {
        let base = (wrap_step(z, dz, nz) * ny + wrap_step(y, dy, ny)) * nx;
        for &(dx, i) in dirs {
            let from = (base + lo) as i64 + dx;
            let theirs = &owner[from as usize..from as usize + (hi - lo)];
            for ((m, &mine), &o) in
                span[lo..hi].iter_mut().zip(&owner[own + lo..own + hi]).zip(theirs)
            {
                *m |= (((o != mine) & (o != WALL_OWNER)) as u32) << i;
            }
            for (e, x) in [0, nx - 1].into_iter().enumerate() {
                let n = base + wrap_step(x, dx, nx);
                if owner[n] != owner[own + x] && owner[n] != WALL_OWNER {
                    ends[e] |= 1 << i;
                }
            }
        }
    }
    masks.extend(nodes.iter().map(|&(x, _)| match x as usize {
        0 => ends[0],
        x if x == nx - 1 => ends[1],
        x => span[x],
    }));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every link `find_links` marks, and only those, against the definition checked node by
    /// node: from a particle node along `c_i` to a node that is not a wall and not covered by
    /// the same particle — with a wall under the particles, a second particle beside the first,
    /// nodes on the periodic x faces, a wall added after the owner field was built, and then
    /// the particles moved (the rows that changed and their neighbours found again, the rest
    /// kept from the call before).
    #[test]
    fn links_leave_the_particle_to_fluid_and_other_particles_never_into_walls() {
        let mut lat = Lattice::new(16, 12, 10, 0.8).unwrap();
        for (x, y) in (0..16).flat_map(|x| (0..12).map(move |y| (x, y))) {
            lat.set_solid(x, y, 0, 1);
        }
        // Body 0: a 2 × 2 × 2 cube, shifted by `dx` and grown by `grow` cells along y; the
        // rest single nodes, some on the x faces.
        let fill = |lat: &mut Lattice, dx: i64, grow: i64| {
            lat.particles.clear();
            for id in 0..4 {
                lat.particles.add_body(id, [8.0, 6.0, 2.0], [0.0; 3], [0.0; 3]).unwrap();
            }
            let mut add = |x: i64, y: i64, z: i64, body: usize| {
                lat.particles.add(body, [x, y, z], 1.0).unwrap()
            };
            for (x, y, z) in
                (7..9).flat_map(|x| (5..7 + grow).flat_map(move |y| (1..3).map(move |z| (x, y, z))))
            {
                add(x + dx, y, z, 0);
            }
            add(9, 5, 1, 1);
            add(0, 3, 1, 2);
            add(15, 3, 1, 2);
            add(15, 8, 2, 3);
        };
        let check = |lat: &Lattice| {
            let owner = |c: usize| {
                (0..lat.particles.rows())
                    .flat_map(|r| {
                        lat.particles
                            .row(r)
                            .iter()
                            .map(move |n| (r * lat.nx + n.x as usize, n.body()))
                    })
                    .find(|&(at, _)| at == c)
                    .map(|(_, body)| body)
            };
            let mut links = 0;
            for (z, y) in (0..lat.nz).flat_map(|z| (0..lat.ny).map(move |y| (z, y))) {
                let row = z * lat.ny + y;
                for (k, n) in lat.particles.row(row).iter().enumerate() {
                    let x = n.x as usize;
                    let mut expected = 0u32;
                    for (i, &c) in C.iter().enumerate().skip(1) {
                        let to = lat.neighbour(x, y, z, c, 1);
                        if !lat.is_solid(to) && owner(to) != Some(n.body()) {
                            expected |= 1 << i;
                        }
                    }
                    assert_eq!(
                        lat.links[row][k],
                        expected,
                        "node ({x}, {y}, {z}) of particle {}",
                        n.body()
                    );
                    links += expected.count_ones();
                }
            }
            links
        };
        fill(&mut lat, 0, 0);
        lat.find_links();
        let before = check(&lat);
        // A wall beside particle 0: the owner field is rebuilt and the links into it go.
        lat.set_solid(6, 5, 1, 1);
        lat.find_links();
        let after = check(&lat);
        assert!(before > 100 && after < before, "{before} links, then {after}");
        // Refilled as it was: nothing changed, everything kept.
        fill(&mut lat, 0, 0);
        lat.find_links();
        assert!(lat.changed.iter().all(|&c| !c));
        assert_eq!(check(&lat), after);
        // Particle 0 one cell along x onto particle 1's node (which it takes: same d_B, added
        // first), then grown along y into rows of its own: the links of the unchanged rows
        // around them change too.
        for (dx, grow) in [(1, 0), (1, 1)] {
            fill(&mut lat, dx, grow);
            lat.find_links();
            let changed = lat.changed.iter().filter(|&&c| c).count();
            assert!(changed > 0 && changed < lat.particles.rows(), "{changed} rows changed");
            check(&lat);
        }
    }
}
