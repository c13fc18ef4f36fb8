use axiscal::blind::{BlindOptions, draw_effect, simulate_case};
use axiscal::calibration::procedure::{CalibrationOptions, calibrate};
use axiscal::diagnosis::*;
use axiscal::robot::RobotDescription;
use rand::{SeedableRng, rngs::StdRng};
fn main() {
    let desc = RobotDescription::asea_irb6l();
    let key = draw_effect("none", 0, 100, &desc, &mut StdRng::seed_from_u64(0));
    let set = simulate_case(&key, &desc, &BlindOptions::default()).unwrap();
    let cal = calibrate(&set, &desc, &CalibrationOptions::default()).unwrap();
    let clean = clean_positions(&set, &cal, &desc).unwrap();
    for noise in [0.0, 1e-5, 0.19e-3] {
        let r = replica(&set, &clean, noise, false, &mut StdRng::seed_from_u64(3)).unwrap();
        let cal2 = calibrate(&r, &desc, &CalibrationOptions::default()).unwrap();
        let poses = validation_poses(r.rows(), &desc);
        let p = Predictor::new(&cal2.robot, &desc, 20.0, None, RefitScope::Geometry);
        let every: Vec<&Pose> = poses.iter().collect();
        let res = p.residuals(&vec![0.0; p.geometric_count()], &every).unwrap();
        let rms = (res.iter().map(|x| x * x).sum::<f64>() / (res.len() / 3) as f64).sqrt() * 1e3;
        println!("noise {noise}: validation rms {rms:.4} mm");
    }
}
