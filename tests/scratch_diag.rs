use axiscal::calibration::procedure::{CalibrationOptions, calibrate};
use axiscal::campaign::{AnalyticArm, CalibrationPlan, ValidationPlan, simulate_campaign};
use axiscal::evaluation::{JointRanges, Region, random_poses};
use axiscal::measurement::{MeasurementModel, MeasurementSet};
use axiscal::robot::{Controller, RobotDescription, TruthRobot};
use rand::{SeedableRng, rngs::StdRng};

fn err(truth: &TruthRobot, cal: &TruthRobot, qs: &[Vec<f64>], c: &Controller, t0: &nalgebra::Point3<f64>) -> f64 {
    let (mt, mc) = (truth.model(), cal.model());
    let mut s = 0.0;
    for q in qs {
        let a = mt.world_from_tool(&truth.joint_values(c, q).unwrap()) * t0;
        let b = mc.world_from_tool(&cal.joint_values(c, q).unwrap()) * t0;
        s += (a - b).norm_squared();
    }
    (s / qs.len() as f64).sqrt() * 1e3
}

#[test]
fn diag() {
    let desc = RobotDescription::asea_irb6l();
    let mut truth = TruthRobot::paper_robot();
    for j in &mut truth.joints { j.repeatability_sigma = 0.0; }
    let c = Controller::from_description(&desc);
    let spans = JointRanges::calibrated_spans(&desc, &CalibrationPlan::table1(6));
    let qs: Vec<Vec<f64>> = random_poses(&desc.nominal_model(), &spans, Region::InsideSpans, 50, 5).into_iter().map(|p| p.q_nominal).collect();
    let t0 = desc.tool_targets_m()[0];
    for seed in 1..=3 {
        let mut arm = AnalyticArm::new(truth.clone(), c.clone());
        let val = ValidationPlan { poses: 0, ..ValidationPlan::workspace_default(6) };
        let out = simulate_campaign(&desc, &CalibrationPlan::table1(6), &val, &mut arm, &MeasurementModel::paper_isotropic(), &mut StdRng::seed_from_u64(seed)).unwrap();
        let set = MeasurementSet::new(6, out.rows).unwrap();
        let cal = calibrate(&set, &desc, &CalibrationOptions::default()).unwrap().robot;
        println!("seed {seed}: total {:.3} mm", err(&truth, &cal, &qs, &c, &t0));
        // swap one part at a time from truth into cal
        let mut x = cal.clone(); x.rows = truth.rows.clone(); println!("  rows<-truth {:.3}", err(&truth, &x, &qs, &c, &t0));
        let mut x = cal.clone(); x.placement = truth.placement; println!("  placement<-truth {:.3}", err(&truth, &x, &qs, &c, &t0));
        let mut x = cal.clone(); x.tool_frame = truth.tool_frame; println!("  tool<-truth {:.3}", err(&truth, &x, &qs, &c, &t0));
        for k in 0..6 {
            let mut x = cal.clone(); x.joints[k] = truth.joints[k].clone(); println!("  joint{}<-truth {:.3}  cal offset {:.2e} trans {:?} coupling {:?}", k+1, err(&truth, &x, &qs, &c, &t0), cal.joints[k].transducer_offset, cal.joints[k].transmission, cal.joints[k].coupling_in);
        }
    }
}
