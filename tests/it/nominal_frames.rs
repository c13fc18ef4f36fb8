//! The hand-checked frame figures of NOTES-paper.md: with the nominal Table 2 rows and every
//! joint at 0, z1 up, z2 = z3 = z4 along +x, z5 along +y, z6 down, origins at heights 0 and
//! 0.69 m, the wrist 0.67 m out along +y and frame 6 at y = 0.9025 m.

use approx::assert_relative_eq;
use axiscal::robot::RobotDescription;
use nalgebra::{Isometry3, Point3, Vector3};

#[test]
fn nominal_frames_at_zero_match_the_hand_check() {
    let mut model = RobotDescription::asea_irb6l().nominal_model();
    model.world_from_base = Isometry3::identity();
    let poses = model.poses(&[0.0; 6]);
    let expect_dirs = [
        Vector3::z(),
        Vector3::x(),
        Vector3::x(),
        Vector3::x(),
        Vector3::y(),
        -Vector3::z(),
    ];
    for (k, d) in expect_dirs.iter().enumerate() {
        assert_relative_eq!(*poses.axis(k).direction, *d, epsilon = 1e-12);
    }
    let origins = [
        Point3::new(0.0, 0.0, 0.0),
        Point3::new(0.0, 0.0, 0.0),
        Point3::new(0.0, 0.0, 0.69),
        Point3::new(0.0, 0.67, 0.69),
        Point3::new(0.0, 0.67, 0.69),
        Point3::new(0.0, 0.9025, 0.69),
    ];
    for (k, o) in origins.iter().enumerate() {
        assert_relative_eq!(poses.axis(k).origin_m, *o, epsilon = 1e-12);
    }
    for k in 0..6 {
        let f = poses.world_from_frame[k];
        println!(
            "frame {}: origin {:?} x {:?} y {:?} z {:?}",
            k + 1,
            (f * Point3::origin()).coords.as_slice(),
            (f * Vector3::x()).as_slice(),
            (f * Vector3::y()).as_slice(),
            (f * Vector3::z()).as_slice()
        );
    }
}
