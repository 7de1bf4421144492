//! Helpers shared by the validation examples: command-line options, output folder, CSV
//! writing, timing, fonts.
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

/// Writes `rows` under `header` to `path` atomically ([`discrete_contact::io`]), so a killed
/// run never leaves a half-written file.
pub fn write_csv(path: &Path, header: &str, rows: &[String]) {
    discrete_contact::io::write_atomically(path, |w| {
        writeln!(w, "{header}")?;
        rows.iter().try_for_each(|r| writeln!(w, "{r}"))
    })
    .unwrap_or_else(|e| panic!("{e}"));
}

/// `--checkpoint-every N` (steps) and `--resume`: where and how often a long example saves its
/// runs (`target/validation/checkpoints/`), and whether it goes on from them.
#[derive(Default)]
pub struct Checkpoints {
    /// Save every this many steps (none: never).
    pub every: Option<u64>,
    /// Resume each run from its checkpoint when there is one.
    pub resume: bool,
    /// The folder of the checkpoint files.
    pub dir: PathBuf,
}

impl Checkpoints {
    /// From the command line, files under `out/checkpoints` (created when saving is asked for).
    pub fn from_args(args: &Args, out: &Path) -> Self {
        let every = args
            .value("--checkpoint-every")
            .map(|_| args.number("--checkpoint-every", 0.0) as u64)
            .filter(|&n| n > 0);
        let dir = out.join("checkpoints");
        if every.is_some() {
            fs::create_dir_all(&dir).expect("create target/validation/checkpoints");
        }
        Self { every, resume: args.flag("--resume"), dir }
    }

    /// The checkpoint file called `name`.
    pub fn file(&self, name: &str) -> PathBuf {
        self.dir.join(format!("{name}.ckpt"))
    }

    /// Whether to save after `step`: every N steps, and when the run has `finished`.
    pub fn due(&self, step: u64, finished: bool) -> bool {
        self.every.is_some_and(|n| finished || step % n == 0)
    }

    /// The file to resume from, when resuming was asked for and it exists.
    pub fn resumable(&self, path: &Path) -> bool {
        self.resume && path.exists()
    }
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
    let _ =
        plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
}

/// A figure's drawing area: a PNG canvas of plotters' bitmap backend.
pub type Canvas<'a> =
    plotters::drawing::DrawingArea<plotters::prelude::BitMapBackend<'a>, plotters::coord::Shift>;

/// Draws a `size` (pixels) PNG at `path`: fonts registered, a white canvas handed to `draw`, and
/// the file replaced atomically, so a reader never sees half a figure.
pub fn png(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&Canvas) -> Result<(), Box<dyn std::error::Error>>,
) -> Result<(), Box<dyn std::error::Error>> {
    use plotters::prelude::*;
    register_fonts();
    discrete_contact::io::replace_atomically(
        path,
        |tmp: &Path| -> Result<(), Box<dyn std::error::Error>> {
            let root = BitMapBackend::new(tmp, size).into_drawing_area();
            root.fill(&WHITE)?;
            draw(&root)?;
            root.present()?;
            Ok(())
        },
    )
}

/// Least-squares slope of `ln(err)` against `ln(n)`, negated: the experimental order of
/// convergence.
pub fn eoc(n: &[f64], err: &[f64]) -> f64 {
    let pts: Vec<(f64, f64)> =
        n.iter().zip(err).filter(|(_, e)| **e > 0.0).map(|(n, e)| (n.ln(), e.ln())).collect();
    let m = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (mx, my) = (sx / m, sy / m);
    let (num, den) = pts
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + (p.0 - mx) * (p.1 - my), a.1 + (p.0 - mx).powi(2)));
    -num / den
}

/// Command-line options: `--name value` pairs and flags.
pub struct Args(Vec<String>);

impl Args {
    /// The process's arguments, checked against the example's source `source` (pass
    /// `include_str!("<example>.rs")`): its leading `//!` doc is the usage text, and every
    /// `--option` it names is known. `--help` prints that text and exits; an option it does not
    /// name is refused (exit 2) rather than ignored — a mistyped option would otherwise start
    /// the default run, which can take an hour.
    pub fn from_env(source: &str) -> Self {
        let usage: String = source
            .lines()
            .map_while(|l| l.strip_prefix("//!"))
            .map(|l| format!("{}\n", l.strip_prefix(' ').unwrap_or(l)))
            .collect();
        let args: Vec<String> = std::env::args().collect();
        if args.iter().skip(1).any(|a| a == "--help" || a == "-h") {
            print!("{usage}");
            std::process::exit(0);
        }
        let known = |a: &str| {
            usage.match_indices(a).any(|(i, _)| {
                !usage[i + a.len()..].starts_with(|c: char| c.is_ascii_alphanumeric() || c == '-')
            })
        };
        if let Some(bad) = args.iter().skip(1).find(|a| a.starts_with("--") && !known(a)) {
            eprintln!("unknown option {bad}; the options are (--help prints this):\n\n{usage}");
            std::process::exit(2);
        }
        Self(args)
    }

    /// Whether a wet run takes the film model (the default, or `--lubrication`) rather than
    /// the enlargement model (`--enlargement-model`); naming both is an error.
    pub fn film_model(&self) -> Result<bool, discrete_contact::Error> {
        match (self.flag("--lubrication"), self.flag("--enlargement-model")) {
            (true, true) => Err(discrete_contact::Error::InvalidArgument {
                name: "--enlargement-model",
                allowed: "without --lubrication (one wet contact model)",
            }),
            (_, enlargement) => Ok(!enlargement),
        }
    }
    /// Whether `name` was given.
    pub fn flag(&self, name: &str) -> bool {
        self.0.iter().any(|a| a == name)
    }
    /// The word after `name`.
    pub fn value(&self, name: &str) -> Option<&str> {
        self.0.iter().position(|a| a == name).and_then(|i| self.0.get(i + 1)).map(String::as_str)
    }
    /// The number after `name` (a clear panic when it is not one), or `default`.
    pub fn number(&self, name: &str, default: f64) -> f64 {
        self.value(name)
            .map(|v| v.parse().unwrap_or_else(|_| panic!("{name}: not a number: {v}")))
            .unwrap_or(default)
    }
    /// The comma-separated numbers after `name`, or `default`.
    pub fn list(&self, name: &str, default: &[f64]) -> Vec<f64> {
        self.value(name)
            .map(|v| {
                v.split(',')
                    .map(|x| {
                        x.trim()
                            .parse()
                            .unwrap_or_else(|_| panic!("{name}: not a number list: {v}"))
                    })
                    .collect()
            })
            .unwrap_or_else(|| default.to_vec())
    }
}

/// Draws `chart`'s legend at `position`: `size`-point labels in a bordered, light box.
pub fn legend<'a, 'b: 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut plotters::chart::ChartContext<'a, plotters::prelude::BitMapBackend<'b>, CT>,
    position: plotters::chart::SeriesLabelPosition,
    size: u32,
) -> Result<(), Box<dyn std::error::Error>> {
    use plotters::prelude::*;
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", size))
        .position(position)
        .draw()?;
    Ok(())
}
