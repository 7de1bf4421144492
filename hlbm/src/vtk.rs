//! Legacy-VTK output (structured points, binary) of density, velocity and `d_B` for ParaView.
//! Written to a temporary file and renamed ([`write_atomically`]), so a killed run leaves no
//! half-written file.

use std::io::{BufWriter, Write};
use std::path::Path;

use crate::error::{Error, Result};
use crate::lattice::Lattice;

fn io(path: &Path, e: std::io::Error) -> Error {
    Error::Io { path: path.display().to_string(), message: e.to_string() }
}

/// Writes `path` complete or not at all: `write` fills a temporary file in the same folder,
/// which is flushed to disk and renamed over `path` (removed if `write` fails).
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let tmp = tempfile::NamedTempFile::new_in(dir).map_err(|e| io(path, e))?;
    let mut w = BufWriter::new(tmp);
    write(&mut w).and_then(|()| w.flush()).map_err(|e| io(path, e))?;
    let tmp = w.into_inner().map_err(|e| io(path, e.into_error()))?;
    tmp.as_file().sync_all().map_err(|e| io(path, e))?;
    tmp.persist(path).map_err(|e| io(path, e.error))?;
    Ok(())
}

/// Writes `lattice`'s density, velocity and solid fraction to `path` (`.vtk`), with spacing
/// `dx` (m) and velocities scaled by `velocity_scale` (lattice → m/s).
pub fn write(lattice: &Lattice, path: &Path, dx: f64, velocity_scale: f64) -> Result<()> {
    let [nx, ny, nz] = lattice.dims();
    write_atomically(path, |w| {
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
                for p in lattice.particles.row(z * ny + y) {
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
    })
}
