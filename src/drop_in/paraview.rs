//! A ParaView time series of the handled bodies and their contacts.
//!
//! Each [`ParaViewSeries::write`] adds one time to the series in its folder, as two VTK XML
//! PolyData files (ASCII, every number in SI units and printed in full, f64 `{:e}`), `n`
//! counting the writes from 0:
//!
//! - `<stem>_bodies_<n>.vtp`: one point (and vertex) per rigid body — fixed, kinematic or
//!   dynamic — with at least one collider handed to the contacts, at its centre of mass (m),
//!   in the order of the bodies' handles. Point data: `velocity` (m/s) and
//!   `angular_velocity` (rad/s), `handle` (the body handle's index) and `size`, the largest
//!   bounding-sphere radius of its handled colliders (m; a half-space counts 0), a scale for
//!   ParaView's Glyph filter.
//! - `<stem>_contacts_<n>.vtp`: one polyline per live contact
//!   ([`DiscreteContacts::contacts`], in their order) — a force chain — through three points:
//!   the centre of mass of collider A's body, the contact point, and that of B's body (the
//!   image nearest A's across a periodic box's faces); a collider that is fixed or has no body
//!   ends its line at the contact point. Cell data: `force_on_a` (N), `normal_force` (N,
//!   positive pushes the bodies apart), `normal` (from B to A), `volume` (m³), `indentation`
//!   (m), `sliding` (0 or 1) and `colliders` (the handles' indices of A and B).
//! - `<stem>.pvd`: the collection ParaView opens, rewritten after each write, listing every
//!   time written so far with its two files as `part="0"` (bodies) and `part="1"` (contacts).
//!
//! Every file is written atomically ([`crate::io`]); a write that fails adds no time to the
//! collection, and the next one writes its files again.

use super::*;
use crate::error::check_range;
use crate::io::{io_error, write_atomically};
use std::io::{self, Write};
use std::ops::Bound::Unbounded;
use std::path::PathBuf;

/// A ParaView time series of a drop-in's bodies and contacts (see the module's docs for the
/// files and their fields).
#[derive(Clone, Debug)]
pub struct ParaViewSeries {
    dir: PathBuf,
    stem: String,
    times: Vec<Real>,
}

impl ParaViewSeries {
    /// A series written to folder `dir` (created if missing) under file names starting with
    /// `stem`. Errors: [`Error::InvalidArgument`] for a stem that is empty, names a folder or
    /// holds one of `&<>"'`; [`Error::Io`] when the folder cannot be created.
    pub fn new(dir: impl Into<PathBuf>, stem: &str) -> Result<Self> {
        let plain = std::path::Path::new(stem).file_name() == Some(stem.as_ref())
            && !stem.contains(['&', '<', '>', '"', '\'']);
        if !plain {
            return Err(Error::InvalidArgument {
                name: "stem",
                allowed: "a file name without a folder or any of &<>\"'",
            });
        }
        let dir = dir.into();
        std::fs::create_dir_all(&dir).map_err(|e| io_error(&dir, e))?;
        Ok(Self { dir, stem: stem.to_owned(), times: Vec::new() })
    }

    /// The collection file, `<stem>.pvd` in the series' folder.
    pub fn collection(&self) -> PathBuf {
        self.dir.join(format!("{}.pvd", self.stem))
    }

    /// Writes the bodies and live contacts of `world` as `contacts` left them after its last
    /// step, for `time` (s), and rewrites the collection. Errors:
    /// [`Error::InvalidParameter`] for a time that is not finite or not later than the last
    /// one written; [`Error::Io`] when a file cannot be written.
    pub fn write(
        &mut self,
        contacts: &DiscreteContacts,
        world: &PhysicsWorld,
        time: Real,
    ) -> Result<()> {
        let after = self.times.last().map_or(Unbounded, |&t| Excluded(t));
        check_range(
            "time",
            time,
            (after, Unbounded),
            "finite and later than the last time written",
        )?;
        let n = self.times.len();
        write_atomically(&self.dir.join(self.file("bodies", n)), |w| {
            write_bodies(w, contacts, world)
        })?;
        write_atomically(&self.dir.join(self.file("contacts", n)), |w| {
            write_contacts(w, contacts, world)
        })?;
        self.times.push(time);
        let listed = write_atomically(&self.collection(), |w| self.write_collection(w));
        if listed.is_err() {
            self.times.pop();
        }
        listed
    }

    /// The name of the `n`-th write's file of `kind`.
    fn file(&self, kind: &str, n: usize) -> String {
        format!("{}_{kind}_{n:06}.vtp", self.stem)
    }

    /// The `.pvd` collection of every time written.
    fn write_collection(&self, w: &mut impl Write) -> io::Result<()> {
        writeln!(w, r#"<?xml version="1.0"?>"#)?;
        writeln!(w, r#"<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">"#)?;
        writeln!(w, "  <Collection>")?;
        for (n, t) in self.times.iter().enumerate() {
            for (part, kind) in ["bodies", "contacts"].into_iter().enumerate() {
                let file = self.file(kind, n);
                writeln!(w, r#"    <DataSet timestep="{t:e}" part="{part}" file="{file}"/>"#)?;
            }
        }
        writeln!(w, "  </Collection>\n</VTKFile>")
    }
}

/// The bodies file: every body with a handled collider, at its centre of mass.
fn write_bodies(
    w: &mut impl Write,
    contacts: &DiscreteContacts,
    world: &PhysicsWorld,
) -> io::Result<()> {
    let mut sizes = std::collections::BTreeMap::<_, (RigidBodyHandle, Real)>::new();
    for (&c, h) in &contacts.handled {
        let Some(b) = world.colliders.get(c).and_then(|co| co.parent()) else { continue };
        if world.bodies.get(b).is_some() {
            let size = sizes.entry(b.into_raw_parts()).or_insert((b, 0.0));
            if h.radius.is_finite() {
                size.1 = size.1.max(h.radius);
            }
        }
    }
    let bodies: Vec<_> = sizes.into_values().map(|(b, size)| (b, &world.bodies[b], size)).collect();
    let n = bodies.len();
    begin_piece(w, n, ("Verts", n))?;
    floats(w, "points", 3, bodies.iter().flat_map(|b| vector(b.1.center_of_mass()).to_array()))?;
    writeln!(w, "      </Points>\n      <PointData>")?;
    floats(w, "velocity", 3, bodies.iter().flat_map(|b| vector(b.1.linvel()).to_array()))?;
    floats(w, "angular_velocity", 3, bodies.iter().flat_map(|b| vector(b.1.angvel()).to_array()))?;
    integers(w, "UInt32", "handle", 1, bodies.iter().map(|b| b.0.into_raw_parts().0.into()))?;
    floats(w, "size", 1, bodies.iter().map(|b| b.2))?;
    writeln!(w, "      </PointData>")?;
    end_piece(w, "Verts", n, 1)
}

/// The contacts file: a polyline per live contact, A's centre to the contact point to B's.
fn write_contacts(
    w: &mut impl Write,
    contacts: &DiscreteContacts,
    world: &PhysicsWorld,
) -> io::Result<()> {
    let readings: Vec<&ContactReading> = contacts.contacts().collect();
    // A collider's end of a line: its body's centre of mass, or the contact point for a
    // collider that is fixed or has no body.
    let centre = |c: ColliderHandle, point: Vector| {
        world
            .colliders
            .get(c)
            .and_then(|co| world.bodies.get(co.parent()?))
            .filter(|rb| !rb.is_fixed())
            .map_or(point, |rb| vector(rb.center_of_mass()))
    };
    let points = readings.iter().flat_map(|r| {
        let a = centre(r.colliders.0, r.point);
        let b = centre(r.colliders.1, r.point);
        let b = b + contacts.periodic.map_or(Vector::ZERO, |p| p.nearest_image_shift(a, b));
        [a, r.point, b].into_iter().flat_map(|v| v.to_array())
    });
    let n = readings.len();
    begin_piece(w, 3 * n, ("Lines", n))?;
    floats(w, "points", 3, points)?;
    writeln!(w, "      </Points>\n      <CellData>")?;
    floats(w, "force_on_a", 3, readings.iter().flat_map(|r| r.force_on_a.to_array()))?;
    floats(w, "normal_force", 1, readings.iter().map(|r| r.normal_force()))?;
    floats(w, "normal", 3, readings.iter().flat_map(|r| r.normal.to_array()))?;
    floats(w, "volume", 1, readings.iter().map(|r| r.volume))?;
    floats(w, "indentation", 1, readings.iter().map(|r| r.indentation))?;
    integers(w, "UInt8", "sliding", 1, readings.iter().map(|r| r.sliding.into()))?;
    let ends = readings.iter().flat_map(|r| [r.colliders.0, r.colliders.1]);
    integers(w, "UInt32", "colliders", 2, ends.map(|c| c.into_raw_parts().0.into()))?;
    writeln!(w, "      </CellData>")?;
    end_piece(w, "Lines", n, 3)
}

/// Opens a PolyData file's piece of `points` points and `cells` cells of one kind, up to the
/// points' array.
fn begin_piece(w: &mut impl Write, points: usize, (kind, cells): (&str, usize)) -> io::Result<()> {
    writeln!(w, r#"<?xml version="1.0"?>"#)?;
    writeln!(w, r#"<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">"#)?;
    writeln!(w, "  <PolyData>")?;
    let counts = ["Verts", "Lines", "Strips", "Polys"]
        .map(|k| format!(r#" NumberOf{k}="{}""#, if k == kind { cells } else { 0 }))
        .concat();
    writeln!(w, r#"    <Piece NumberOfPoints="{points}"{counts}>"#)?;
    writeln!(w, "      <Points>")
}

/// Closes the piece with its `cells` cells of `kind`, each of `size` consecutive points.
fn end_piece(w: &mut impl Write, kind: &str, cells: usize, size: usize) -> io::Result<()> {
    writeln!(w, "      <{kind}>")?;
    integers(w, "Int64", "connectivity", 1, 0..(cells * size) as u64)?;
    integers(w, "Int64", "offsets", 1, (1..=cells as u64).map(|k| k * size as u64))?;
    writeln!(w, "      </{kind}>\n    </Piece>\n  </PolyData>\n</VTKFile>")
}

/// An ASCII `DataArray` of f64 `components`-tuples, one tuple a line.
fn floats(
    w: &mut impl Write,
    name: &str,
    components: usize,
    values: impl IntoIterator<Item = Real>,
) -> io::Result<()> {
    array(w, "Float64", name, components, values, |w, x| write!(w, "{x:e}"))
}

/// An ASCII `DataArray` of VTK integer type `ty`, `components`-tuples, one tuple a line.
fn integers(
    w: &mut impl Write,
    ty: &str,
    name: &str,
    components: usize,
    values: impl IntoIterator<Item = u64>,
) -> io::Result<()> {
    array(w, ty, name, components, values, |w, x| write!(w, "{x}"))
}

/// An ASCII `DataArray` of `values`, each printed by `print`.
fn array<W: Write, T>(
    w: &mut W,
    ty: &str,
    name: &str,
    components: usize,
    values: impl IntoIterator<Item = T>,
    print: impl Fn(&mut W, T) -> io::Result<()>,
) -> io::Result<()> {
    write!(
        w,
        r#"        <DataArray type="{ty}" Name="{name}" NumberOfComponents="{components}" format="ascii">"#
    )?;
    for (k, x) in values.into_iter().enumerate() {
        w.write_all(if k % components == 0 { b"\n          " } else { b" " })?;
        print(w, x)?;
    }
    writeln!(w, "\n        </DataArray>")
}
