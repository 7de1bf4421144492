//! The fluid's total mass and momentum, reduced per z-slab on all cores and summed in slab
//! order, so the result does not depend on the thread count.

use rayon::prelude::*;

use super::storage::{Pop, Storage};
use super::Lattice;
use crate::d3q19::{C, OPP, Q};

impl Lattice {
    /// Total mass and momentum of the fluid nodes.
    pub fn totals(&self) -> (f64, [f64; 3]) {
        if self.has_solid() {
            self.totals_by_node()
        } else {
            self.totals_without_walls()
        }
    }

    /// [`Lattice::totals`] node by node, walls and all.
    fn totals_by_node(&self) -> (f64, [f64; 3]) {
        // Per z-slab on all cores, slabs summed in order: the same sum for any thread count.
        let slabs: Vec<(f64, [f64; 3])> = (0..self.nz)
            .into_par_iter()
            .map(|z| {
                let (mut m, mut p) = (0.0, [0.0; 3]);
                for y in 0..self.ny {
                    for x in 0..self.nx {
                        if self.kind[self.index(x, y, z)] == 0 {
                            let (rho, u) = self.density_velocity(x, y, z);
                            m += rho;
                            for d in 0..3 {
                                p[d] += rho * u[d];
                            }
                        }
                    }
                }
                (m, p)
            })
            .collect();
        add_slabs(slabs)
    }

    /// [`Lattice::totals`] of a lattice without solid nodes: every stored population belongs
    /// to a fluid node, so each direction's total is one contiguous sum over its slot (slot
    /// `i` in even steps, `ī` in odd ones) — a streaming read, where the node-by-node sum
    /// gathers each node's populations from 19 arrays (and, in odd steps, from its
    /// neighbours).
    fn totals_without_walls(&self) -> (f64, [f64; 3]) {
        fn sum<T: Pop>(f: &[T], i: usize) -> f64 {
            f.iter().map(|v| v.get(i)).sum()
        }
        let (n, slab) = (self.stride, self.nx * self.ny);
        let odd = self.time % 2 == 1;
        let slabs: Vec<(f64, [f64; 3])> = (0..self.nz)
            .into_par_iter()
            .map(|z| {
                let (mut m, mut p) = (0.0, [0.0; 3]);
                for i in 0..Q {
                    let at = (if odd { OPP[i] } else { i }) * n + z * slab;
                    let s = match self.storage {
                        Storage::F64 => sum(&self.f.as_slice::<f64>()[at..at + slab], i),
                        Storage::F32 => sum(&self.f.as_slice::<f32>()[at..at + slab], i),
                    };
                    m += s;
                    for d in 0..3 {
                        p[d] += C[i][d] as f64 * s;
                    }
                }
                (m, p)
            })
            .collect();
        add_slabs(slabs)
    }
}

/// The mass and momentum of all slabs, added in slab order (the same sum for any thread
/// count).
fn add_slabs(slabs: Vec<(f64, [f64; 3])>) -> (f64, [f64; 3]) {
    slabs.into_iter().fold((0.0, [0.0; 3]), |(m, p), (ms, ps)| {
        (m + ms, [p[0] + ps[0], p[1] + ps[1], p[2] + ps[2]])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The contiguous sums of a lattice without walls give the node-by-node totals (even and
    /// odd steps, both storages) to round-off.
    #[test]
    fn totals_without_walls_are_the_node_by_node_totals() {
        for storage in [Storage::F64, Storage::F32] {
            let mut lat = Lattice::new(12, 10, 8, 0.7).unwrap();
            lat.set_storage(storage);
            lat.initialise(|x, y, z| {
                (
                    1.0 + 0.01 * (x as f64 * 0.7 + y as f64 * 0.3).sin(),
                    [0.02 * (z as f64).cos(), -0.01, 0.03 * (y as f64 * 0.5).sin()],
                )
            });
            lat.set_body_acceleration([1e-5, 2e-5, -3e-5]);
            for _ in 0..2 {
                lat.step().unwrap();
                let (m, p) = lat.totals_without_walls();
                let (m0, p0) = lat.totals_by_node();
                assert!(
                    (m - m0).abs() < 1e-10 * m0,
                    "{storage:?}, step {}: mass {m} vs {m0}",
                    lat.time()
                );
                for d in 0..3 {
                    assert!(
                        (p[d] - p0[d]).abs() < 1e-10 * m0,
                        "{storage:?}, step {}: momentum {p:?} vs {p0:?}",
                        lat.time()
                    );
                }
                assert!(
                    p0.iter().all(|c| c.abs() > 1.0),
                    "a flow with momentum on every axis: {p0:?}"
                );
            }
        }
    }
}
