//! The paper scenario closed in the loop.
use axiscal::evaluation::{PaperScenario, run_paper_scenario};
use axiscal::measurement::MeasurementModel;

#[test]
fn print_numbers() {
    for seed in 1..=3 {
        let s = PaperScenario { seed, evaluation_seed: 9283, random_poses: 30, instrument: MeasurementModel::paper_isotropic() };
        let out = run_paper_scenario(&s).unwrap();
        for r in &out.report.regions {
            let f = |s: &[axiscal::evaluation::Stats; 3]| format!("{:.4}/{:.4}/{:.4}", s[0].rms, s[1].rms, s[2].rms);
            println!("seed {seed} {:?}: pos {} ori {} mpos {} mori {} ratio {:?} model ratio {:?} fail {}", r.region, f(&r.position_mm), f(&r.orientation_rad), f(&r.model_position_mm), f(&r.model_orientation_rad), r.ratio_to_floor, r.model_ratio_to_floor, r.failures);
        }
    }
}
