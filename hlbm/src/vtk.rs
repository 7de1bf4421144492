//! Legacy-VTK output (structured points, binary) of density, velocity and `d_B` for ParaView,
//! to any writer: where and how the file is written (atomically, in the crates that use this
//! one) is the caller's business.

use std::io::Write;

use crate::lattice::Lattice;

/// Writes `lattice`'s density, velocity and solid fraction to `w` as a legacy VTK file, with
/// spacing `dx` (m) and velocities scaled by `velocity_scale` (lattice → m/s).
pub fn write_to(
    w: &mut dyn Write,
    lattice: &Lattice,
    dx: f64,
    velocity_scale: f64,
) -> std::io::Result<()> {
    let [nx, ny, nz] = lattice.dims();
    writeln!(
        w,
        "# vtk DataFile Version 3.0\nhlbm step {}\nBINARY\nDATASET STRUCTURED_POINTS",
        lattice.time()
    )?;
    writeln!(
        w,
        "DIMENSIONS {nx} {ny} {nz}\nORIGIN 0 0 0\nSPACING {dx} {dx} {dx}\nPOINT_DATA {}",
        nx * ny * nz
    )?;
    let mut rho = Vec::with_capacity(nx * ny * nz);
    let mut vel = Vec::with_capacity(nx * ny * nz);
    let mut db = vec![0.0f32; nx * ny * nz];
    for z in 0..nz {
        for y in 0..ny {
            for p in lattice.particles().row(z * ny + y) {
                db[lattice.index(p.x as usize, y, z)] = p.d_b as f32;
            }
            for x in 0..nx {
                let (r, u) = if lattice.is_solid(lattice.index(x, y, z)) {
                    (1.0, [0.0; 3])
                } else {
                    lattice.density_velocity(x, y, z)
                };
                rho.push(r as f32);
                vel.extend(u.map(|v| (v * velocity_scale) as f32));
            }
        }
    }
    let be = |v: &[f32]| v.iter().flat_map(|x| x.to_be_bytes()).collect::<Vec<u8>>();
    writeln!(w, "SCALARS density float 1\nLOOKUP_TABLE default")?;
    w.write_all(&be(&rho))?;
    writeln!(w, "\nVECTORS velocity float")?;
    w.write_all(&be(&vel))?;
    writeln!(w, "\nSCALARS d_B float 1\nLOOKUP_TABLE default")?;
    w.write_all(&be(&db))?;
    writeln!(w)
}
