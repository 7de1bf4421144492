//! Helpers shared by the validation examples: output folder, CSV writing, timing, fonts.
#![allow(dead_code)]

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// `target/validation/`, created if missing.
pub fn output_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target").join("validation");
    fs::create_dir_all(&dir).expect("create target/validation");
    dir
}

/// Writes `rows` under `header` to `path` atomically (a temporary file renamed into place),
/// so a killed run never leaves a half-written file.
pub fn write_csv(path: &Path, header: &str, rows: &[String]) {
    let tmp = path.with_extension("csv.tmp");
    {
        let mut f = fs::File::create(&tmp).expect("create csv");
        writeln!(f, "{header}").unwrap();
        for r in rows {
            writeln!(f, "{r}").unwrap();
        }
        f.sync_all().unwrap();
    }
    fs::rename(&tmp, path).expect("rename csv");
}

/// Mean wall time of `f` in µs, repeated until at least `min_ms` have passed.
pub fn time_us(min_ms: f64, mut f: impl FnMut()) -> f64 {
    let start = Instant::now();
    let mut n = 0u64;
    loop {
        f();
        n += 1;
        let el = start.elapsed().as_secs_f64() * 1e3;
        if el >= min_ms {
            return el * 1e3 / n as f64;
        }
    }
}

/// Registers DejaVu Sans as plotters' "sans-serif" (no system fonts needed).
pub fn register_fonts() {
    use plotters::style::FontStyle;
    let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
}

/// Least-squares slope of `ln(err)` against `ln(n)`, negated: the experimental order of
/// convergence.
pub fn eoc(n: &[f64], err: &[f64]) -> f64 {
    let pts: Vec<(f64, f64)> = n.iter().zip(err).filter(|(_, e)| **e > 0.0).map(|(n, e)| (n.ln(), e.ln())).collect();
    let m = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (mx, my) = (sx / m, sy / m);
    let (num, den) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + (p.0 - mx) * (p.1 - my), a.1 + (p.0 - mx).powi(2)));
    -num / den
}
