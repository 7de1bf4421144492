use discrete_contact::validation::hertz::HertzCase;
use discrete_contact::*;
fn main() {
    for case in HertzCase::all() {
        let mut line = format!("{:22}", case.name());
        for mode in [IntegrationMode::Count, IntegrationMode::Subcell] {
            for n in [2, 4, 8, 16, 32] {
                let s = OverlapSettings::new(n, mode).unwrap();
                let t = std::time::Instant::now();
                let e = case.rms_relative_error(&s).unwrap();
                let dt = t.elapsed().as_secs_f64() / 20.0 * 1e6;
                line += &format!(" {}{:2}:{:.4}({:.0}us)", &mode.name()[..1], n, e, dt);
            }
        }
        println!("{line}");
    }
}
