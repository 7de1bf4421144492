//! Checkpoints (feature `checkpoint`, on by default): save a run's state and resume it later
//! with bit-identical results.
//!
//! What a run's state is belongs to the caller: any serde value — typically a tuple of the
//! rapier [`PhysicsWorld`](rapier3d_f64::prelude::PhysicsWorld), the
//! [`DiscreteContacts`](crate::rapier::DiscreteContacts), the
//! `coupling::Fluid` of a wet run and the caller's own counters. Every state
//! type of this crate, rapier's world and the lattice implement `Serialize`/`Deserialize`.
//!
//! A file is written atomically ([`crate::io::replace_atomically`]) and holds a signature,
//! the format version, the writer (this crate and its version), the caller's *kind* label,
//! the payload's length and CRC-32, then the payload (postcard: every `f64` bit kept). Loading
//! refuses — with [`Error::Checkpoint`] naming the problem — a file that is not a checkpoint,
//! another format or crate version, another kind, a truncated or altered file.
//!
//! ```
//! use discrete_contact::prelude::*;
//! use discrete_contact::{checkpoint, rapier::DiscreteContacts};
//! use rapier3d_f64::prelude::*;
//! # use discrete_contact::math::Vector;
//! let mut world = PhysicsWorld::new();
//! let ball = world.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 0.02, 0.0)));
//! world.insert_collider(ColliderBuilder::ball(0.01), Some(ball));
//! let floor = world.insert_body(RigidBodyBuilder::fixed());
//! world.insert_collider(ColliderBuilder::new(SharedShape::halfspace(Vector::Y)), Some(floor));
//! world.integration_parameters.dt = 1e-4;
//! let mut contacts = DiscreteContacts::new(OverlapSettings::new(4, IntegrationMode::Subcell)?, 0.9)?;
//! contacts.handle_all(&mut world, Material::new(1e8, 0.3)?)?;
//!
//! let path = std::env::temp_dir().join("discrete_contact_doc.ckpt");
//! checkpoint::save(&path, "doc/ball", &(&world, &contacts, 0u64))?;
//! let (mut world, mut contacts, _step): (PhysicsWorld, DiscreteContacts, u64) = checkpoint::load(&path, "doc/ball")?;
//! contacts.step(&mut world)?; // goes on exactly as the saved run would have
//! # Ok::<(), discrete_contact::Error>(())
//! ```

use std::io::{Read, Write};
use std::path::Path;

use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::error::{CheckpointProblem, Error, Result};
use crate::io::{io_error, write_atomically};

/// The checkpoint format this build writes and reads; raised whenever a saved type changes
/// (a file of another format is refused with `CheckpointProblem::FormatVersion`).
pub const FORMAT_VERSION: u32 = 8;

/// Signature at the start of every checkpoint (a non-text byte first, as PNG does, so a text
/// file is never mistaken for one).
const MAGIC: [u8; 8] = *b"\x89DCCKPT\n";

/// The writer named in every file: a different crate version may lay its state out
/// differently, so its files are refused rather than misread.
fn writer() -> String {
    format!("{} {}", env!("CARGO_PKG_NAME"), env!("CARGO_PKG_VERSION"))
}

thread_local! {
    /// The typed refusal of a value read from a file (postcard keeps no message of its own).
    static REFUSED: std::cell::RefCell<Option<Error>> = const { std::cell::RefCell::new(None) };
}

/// Passes on a constructor's verdict on a value being read from a checkpoint, keeping a
/// refusal so that [`load`] can name the parameter and its range.
pub(crate) fn checked<T>(verdict: Result<T>) -> Result<T> {
    if let Err(e) = &verdict {
        REFUSED.with(|r| *r.borrow_mut() = Some(e.clone()));
    }
    verdict
}

fn problem(path: &Path, problem: CheckpointProblem) -> Error {
    Error::Checkpoint { path: path.display().to_string(), problem }
}

/// Saves `state` to `path` under the label `kind` (e.g. `"settling/v1"`), atomically: a
/// run killed while saving keeps its previous checkpoint intact.
///
/// Errors: [`Error::Checkpoint`] with [`CheckpointProblem::Encode`] when the state holds
/// something that cannot be saved (a custom SDF — a closure); [`Error::Io`] when the file
/// cannot be written.
pub fn save<T: Serialize + ?Sized>(path: &Path, kind: &str, state: &T) -> Result<()> {
    let payload = postcard::to_stdvec(state).map_err(|e| {
        let why = match e {
            // Postcard drops the refusing type's message; of this crate's types only one refuses.
            postcard::Error::SerdeSerCustom => {
                "a value refused to be saved (of this crate's types only ConvexShape::Custom does: a closure cannot be written to a file)".to_string()
            }
            other => other.to_string(),
        };
        problem(path, CheckpointProblem::Encode(why))
    })?;
    let label = |s: &str| -> Result<u16> {
        u16::try_from(s.len()).map_err(|_| {
            problem(
                path,
                CheckpointProblem::Encode(format!("label longer than 65535 bytes: {s:.40}…")),
            )
        })
    };
    let (writer, kind_len) = (writer(), label(kind)?);
    write_atomically(path, |w| {
        w.write_all(&MAGIC)?;
        w.write_all(&FORMAT_VERSION.to_le_bytes())?;
        w.write_all(&(writer.len() as u16).to_le_bytes())?;
        w.write_all(writer.as_bytes())?;
        w.write_all(&kind_len.to_le_bytes())?;
        w.write_all(kind.as_bytes())?;
        w.write_all(&(payload.len() as u64).to_le_bytes())?;
        w.write_all(&crc32fast::hash(&payload).to_le_bytes())?;
        w.write_all(&payload)
    })
}

/// Reads a checkpoint saved under `kind` into the state it holds.
///
/// Errors: [`Error::Io`] when the file cannot be read; [`Error::Checkpoint`] when it is not
/// a checkpoint, is of another format, crate version or kind, is truncated or altered, or does
/// not decode as `T`.
pub fn load<T: DeserializeOwned>(path: &Path, kind: &str) -> Result<T> {
    // The signature first: a large file of another kind is refused without reading it.
    let mut file = std::fs::File::open(path).map_err(|e| io_error(path, e))?;
    let mut bytes = vec![0u8; MAGIC.len()];
    match file.read_exact(&mut bytes) {
        Ok(()) if bytes == MAGIC => {}
        Err(e) if e.kind() != std::io::ErrorKind::UnexpectedEof => return Err(io_error(path, e)),
        _ => return Err(problem(path, CheckpointProblem::NotACheckpoint)),
    }
    file.read_to_end(&mut bytes).map_err(|e| io_error(path, e))?;
    let payload = payload(&bytes, kind).map_err(|p| problem(path, p))?;
    let decode = |why: String| problem(path, CheckpointProblem::Decode(why));
    REFUSED.with(|r| r.borrow_mut().take());
    match postcard::take_from_bytes(payload) {
        Ok((state, [])) => Ok(state),
        Ok((_, rest)) => {
            Err(decode(format!("{} bytes left over: the file holds a larger state", rest.len())))
        }
        Err(e) => Err(decode(
            REFUSED
                .with(|r| r.borrow_mut().take())
                .map_or_else(|| e.to_string(), |refused| refused.to_string()),
        )),
    }
}

/// Checks a checkpoint's header and checksum; returns its payload.
fn payload<'a>(bytes: &'a [u8], kind: &str) -> core::result::Result<&'a [u8], CheckpointProblem> {
    let mut rest = bytes;
    let mut take = |n: usize| -> core::result::Result<&'a [u8], CheckpointProblem> {
        if rest.len() < n {
            // A header cut short: whatever it announced, the payload is not there.
            return Err(CheckpointProblem::Length { expected: n as u64, found: rest.len() as u64 });
        }
        let (head, tail) = rest.split_at(n);
        rest = tail;
        Ok(head)
    };
    if bytes.len() < MAGIC.len() || take(MAGIC.len())? != MAGIC {
        return Err(CheckpointProblem::NotACheckpoint);
    }
    let found = u32::from_le_bytes(take(4)?.try_into().expect("4 bytes"));
    if found != FORMAT_VERSION {
        return Err(CheckpointProblem::FormatVersion { found, supported: FORMAT_VERSION });
    }
    let mut text = || -> core::result::Result<String, CheckpointProblem> {
        let n = u16::from_le_bytes(take(2)?.try_into().expect("2 bytes")) as usize;
        Ok(String::from_utf8_lossy(take(n)?).into_owned())
    };
    let (by, found_kind) = (text()?, text()?);
    if by != writer() {
        return Err(CheckpointProblem::WrittenBy { found: by, this: writer() });
    }
    if found_kind != kind {
        return Err(CheckpointProblem::Kind { found: found_kind, expected: kind.to_string() });
    }
    let expected = u64::from_le_bytes(take(8)?.try_into().expect("8 bytes"));
    let stored = u32::from_le_bytes(take(4)?.try_into().expect("4 bytes"));
    if rest.len() as u64 != expected {
        return Err(CheckpointProblem::Length { expected, found: rest.len() as u64 });
    }
    let computed = crc32fast::hash(rest);
    if computed != stored {
        return Err(CheckpointProblem::Checksum { stored, computed });
    }
    Ok(rest)
}
