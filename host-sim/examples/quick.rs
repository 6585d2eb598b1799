use estimator_core::{Config, Estimator, Method, Sample};
use estimator_core::units::rad_to_arcsec;
use host_sim::scenario::*;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let kind = ScenarioKind::parse(args.get(1).map(|s| s.as_str()).unwrap_or("paper")).unwrap();
    let seed: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    let p = ScenarioParams::new(kind, seed);
    let g = generate(&p);
    for method in [Method::Windowed, Method::Paper, Method::Traditional] {
        let mut est: Estimator = Estimator::new(Config::with_method(method)).unwrap();
        print!("{:12}", method.name());
        for (row, tr) in g.rows.iter().zip(&g.truth) {
            let s = Sample::from_degrees(row.time_s, row.rotation_deg, row.platform_deg, row.latitude_deg, row.heading_deg, row.roll_deg, row.pitch_deg);
            let out = est.step(&s).unwrap();
            let t = row.time_s as u64;
            if [1000, 2000, 5000, 10000, 20000, 45000, 86400, 172799].contains(&t) {
                if let Some(e) = out.estimate {
                    let err: Vec<String> = (0..4).map(|i| format!("{:+.2}({:.2})", rad_to_arcsec(e.x_rad[i] as f64) - tr.errors_arcsec[i], rad_to_arcsec(e.sigma_rad[i] as f64))).collect();
                    print!("\n  t={t:6} {} {}", err.join(" "), out.status.name());
                }
            }
        }
        println!();
    }
}
