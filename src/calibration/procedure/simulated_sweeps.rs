//! A file's sweeps as a calibrated robot would have measured them: the files without any
//! instrument scale that the coordinate-scale profile's finding is weighed against where the
//! sweeps enter through the held joints' correction
//! ([`crate::calibration::recalibrated::beyond_correction_error`]). Each target's place on its
//! link is read from the file itself (the measured points carried into the link's frame by the
//! model at each row's recorded commands, averaged over the rows of every sweep of its joint
//! with its target id: the procedure takes one target per joint and id, which the held
//! joints' correction moves its sweeps at other poses onto), so the simulated sweeps stand
//! where the file's do, at its commands, on a robot that holds together exactly.

use super::held::target_link;
use crate::measurement::MeasurementSet;
use crate::robot::{Controller, RobotDescription, RobotModel, commands_to_internal};
use nalgebra::{Isometry3, Vector3};
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};
use std::collections::BTreeMap;

/// `set` with each sweep row's coordinates replaced by where `robot` puts its target at the
/// row's commands, plus isotropic Gaussian noise of `sigma_mm` per coordinate drawn from `rng`
/// in row order (module docs). Rows of no sweep (the tool observation, validation poses) and
/// targets other than a sweep's two are kept as measured. `None` where the model cannot pose
/// a row's commands.
pub fn simulated_sweeps<R: Rng + ?Sized>(
    set: &MeasurementSet,
    (desc, robot): (&RobotDescription, &RobotModel),
    sigma_mm: f64,
    rng: &mut R,
) -> Option<MeasurementSet> {
    let posed = row_poses(set, desc, robot)?;
    let mut sums: BTreeMap<(usize, usize), (Vector3<f64>, f64)> = BTreeMap::new();
    for &(i, w) in &posed {
        let m = &set.rows()[i];
        let entry = sums.entry((m.moved_joint, m.target)).or_insert((Vector3::zeros(), 0.0));
        entry.0 += w.inverse_transform_point(&m.position_m()).coords;
        entry.1 += 1.0;
    }
    let moves: Vec<(usize, [f64; 3])> = posed
        .iter()
        .map(|&(i, w)| {
            let m = &set.rows()[i];
            let (sum, count) = sums[&(m.moved_joint, m.target)];
            let at_mm = (w * nalgebra::Point3::from(sum / count)).coords * 1e3;
            let by = std::array::from_fn(|c| {
                let noise: f64 = StandardNormal.sample(rng);
                at_mm[c] + sigma_mm * noise - m.position_mm[c]
            });
            (i, by)
        })
        .collect();
    Some(set.with_rows_moved(&moves))
}

/// Each sweep row of `set` (targets 0 and 1) with the pose of the link carrying its target at
/// the row's recorded commands under `robot` (instrument frame, metres).
fn row_poses(
    set: &MeasurementSet,
    desc: &RobotDescription,
    robot: &RobotModel,
) -> Option<Vec<(usize, Isometry3<f64>)>> {
    let controller = Controller::from_description(desc);
    let phi = robot.phi_model();
    set.rows()
        .iter()
        .enumerate()
        .filter(|(_, m)| (1..=desc.dof()).contains(&m.moved_joint) && m.target <= 1)
        .map(|(i, m)| {
            let u = controller.decouple(&commands_to_internal(desc, &m.cmd)).ok()?;
            let q = robot.joint_values_from_actuators(&u).ok()?;
            let link = target_link(desc, m.moved_joint, m.target);
            Some((i, phi.poses(&q).world_from_link[link]))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibration::procedure::{CalibrationOptions, calibrate};
    use crate::measurement::Measurement;
    use rand::SeedableRng;
    use rand::rngs::ChaCha12Rng;

    /// The UR5e's sweeps: each joint over 60 degrees in 12 steps at three poses (the
    /// reference, joint 1 held at 20 degrees, joint 1 at -20 and joint 2 at 10), every point at
    /// `at_mm`: a file's structure without its places.
    fn sweeps(desc: &RobotDescription, at_mm: [f64; 3]) -> MeasurementSet {
        let n = desc.dof();
        let mut rows = vec![];
        let held: [&[(usize, f64)]; 3] = [&[], &[(0, 20.0)], &[(0, -20.0), (1, 10.0)]];
        for joint in 1..=n {
            for (pose, held) in held.iter().enumerate() {
                let experiment = match pose {
                    0 => format!("axis{joint}"),
                    _ => format!("axis{joint}-{}", pose + 1),
                };
                for step in 0..13 {
                    let mut cmd = vec![0.0; n];
                    held.iter().for_each(|&(j, v)| cmd[j] = v);
                    cmd[joint - 1] += -30.0 + 5.0 * step as f64;
                    rows.push(Measurement {
                        experiment: experiment.clone(),
                        moved_joint: joint,
                        step,
                        target: 0,
                        position_mm: at_mm,
                        cmd,
                        payload_kg: 0.0,
                        temperature_c: 20.0,
                    });
                }
            }
        }
        MeasurementSet::new(n, rows).unwrap()
    }

    /// Simulated without noise, a file is one the robot measures exactly: simulated again it
    /// is unchanged (to rounding), and its calibration fits every joint's three sweeps, moved
    /// to one pose by the held joints' correction, to rounding (one target per joint, on the
    /// link and at the poses the calibration uses). With noise, the points move from there by
    /// the noise asked for: the RMS of 3 x 234 normal draws is within 4 of its standard
    /// deviations (`1 / sqrt(2 n)` relative) of sigma.
    #[test]
    fn a_robot_measures_its_simulated_sweeps_exactly_and_the_noise_is_the_noise_asked() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/robots/ur5e-dh.toml");
        let desc = RobotDescription::from_file(&path).unwrap();
        let robot = RobotModel::ideal(&desc);
        let mut rng = ChaCha12Rng::seed_from_u64(1);
        let exact = simulated_sweeps(&sweeps(&desc, [300.0, 200.0, 400.0]), (&desc, &robot), 0.0, &mut rng).unwrap();
        let again = simulated_sweeps(&exact, (&desc, &robot), 0.0, &mut rng).unwrap();
        let apart = |a: &MeasurementSet, b: &MeasurementSet| -> Vec<f64> {
            a.rows()
                .iter()
                .zip(b.rows())
                .flat_map(|(a, b)| (0..3).map(move |c| a.position_mm[c] - b.position_mm[c]))
                .collect()
        };
        assert!(apart(&exact, &again).iter().all(|d| d.abs() < 1e-9));
        let cal = calibrate(&exact, &desc, &CalibrationOptions::default()).unwrap();
        assert!(cal.held_passes > 1, "the held joints' correction ran");
        for axis in &cal.axes {
            assert!(
                axis.residual_rms_mm < 1e-6,
                "joint {}: {} mm",
                axis.joint,
                axis.residual_rms_mm
            );
        }
        let sigma_mm = 0.1;
        let noisy = simulated_sweeps(&exact, (&desc, &robot), sigma_mm, &mut rng).unwrap();
        let d = apart(&noisy, &exact);
        let rms = (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt();
        let bound = 4.0 / (2.0 * d.len() as f64).sqrt();
        assert!((rms / sigma_mm - 1.0).abs() < bound, "{rms} mm over {} draws", d.len());
    }
}
