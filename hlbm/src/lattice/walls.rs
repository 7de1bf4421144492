//! Walls: solid nodes with halfway bounce-back, resting or moving, and the checks that a
//! non-periodic axis is closed by them. The sweep reads a node's kind only in blocks that
//! [`Lattice::set_solid`] marked as next to a solid node.

use super::Lattice;
use crate::d3q19::LANES;
use crate::error::{Error, Result};

/// Fluid or solid (wall) node: 0 is fluid, 1 a resting wall, `k > 1` a wall made by
/// [`Lattice::add_wall`].
pub type NodeKind = u8;

impl Lattice {
    /// Registers a wall moving with `velocity` (lattice units); returns its kind for
    /// [`Lattice::set_solid`].
    pub fn add_wall(&mut self, velocity: [f64; 3]) -> Result<NodeKind> {
        if self.wall_velocity.len() > 254 {
            return Err(Error::InvalidParameter {
                name: "walls",
                value: 255.0,
                allowed: "at most 254 walls",
            });
        }
        self.wall_velocity.push(velocity);
        Ok((self.wall_velocity.len() - 1) as NodeKind)
    }

    /// Marks cell `(x, y, z)` fluid (`0`), resting wall (`1`) or a wall `kind` returned by
    /// [`Lattice::add_wall`].
    pub fn set_solid(&mut self, x: usize, y: usize, z: usize, kind: NodeKind) {
        if kind as usize >= self.wall_velocity.len() {
            self.wall_velocity.resize(kind as usize + 1, [0.0; 3]);
        }
        let c = self.index(x, y, z);
        self.kind[c] = kind;
        self.any_solid = std::sync::OnceLock::new();
        // The owner field marks walls: rebuilt when next needed.
        self.owner.clear();
        // Blocks within one cell of a solid node take the solid-aware path.
        let (nx, ny, nz) = (self.nx as i64, self.ny as i64, self.nz as i64);
        let blocks = self.nx.div_ceil(LANES);
        for dz in -1..=1i64 {
            for dy in -1..=1i64 {
                for dx in -1..=1i64 {
                    let (xx, yy, zz) = (
                        (x as i64 + dx).rem_euclid(nx),
                        (y as i64 + dy).rem_euclid(ny),
                        (z as i64 + dz).rem_euclid(nz),
                    );
                    self.slow_block[(zz * ny + yy) as usize * blocks + xx as usize / LANES] = true;
                }
            }
        }
    }

    /// Closes the domain with resting walls on the faces of the non-periodic axes.
    pub fn close_faces(&mut self, periodic: [bool; 3]) {
        let [nx, ny, nz] = self.dims();
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let edge = (!periodic[0] && (x == 0 || x == nx - 1))
                        || (!periodic[1] && (y == 0 || y == ny - 1))
                        || (!periodic[2] && (z == 0 || z == nz - 1));
                    if edge {
                        self.set_solid(x, y, z, 1);
                    }
                }
            }
        }
    }

    /// Checks that a fluid node never reaches across a non-periodic face: the faces of those
    /// axes must be solid.
    pub fn check_closed(&self, periodic: [bool; 3]) -> Result<()> {
        let [nx, ny, nz] = self.dims();
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let edge = [(x, nx), (y, ny), (z, nz)]
                        .iter()
                        .zip(periodic)
                        .any(|(&(v, n), p)| !p && (v == 0 || v == n - 1));
                    if edge && self.kind[self.index(x, y, z)] == 0 {
                        return Err(Error::OpenBoundary { x, y, z });
                    }
                }
            }
        }
        Ok(())
    }

    /// Whether any node is solid (a scan of the node kinds, ~1 B per node, the first time
    /// after a change).
    pub fn has_solid(&self) -> bool {
        *self.any_solid.get_or_init(|| self.kind.iter().any(|&k| k != 0))
    }

    /// Whether cell `c` is solid.
    pub fn is_solid(&self, c: usize) -> bool {
        self.kind[c] != 0
    }
}
