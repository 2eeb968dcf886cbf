//! Law evaluations per second (stress + consistent tangent + trial history) for every law
//! of `loam-laws` in elastic and plastic states, single-threaded.
//!
//! Run: `cargo bench -p loam-laws --bench law_throughput`. Plain `std::time::Instant`
//! timing (no benchmark framework, to keep the dependency tree small): each case is warmed
//! up, then evaluated repeatedly for about 0.3 s; the table reports the mean rate.

use std::hint::black_box;
use std::time::{Duration, Instant};

use loam_laws::multiplicative::hencky_strain;
use loam_laws::{ConstitutiveLaw, Kinematics, MaterialSpec, StressResponse, TangentRequest};
use nalgebra::{Matrix3, Rotation3, Vector3};
use serde_json::json;

fn stretch(eps: [f64; 3]) -> Matrix3<f64> {
    let r = Rotation3::from_euler_angles(0.3, -0.4, 0.7).into_inner();
    r * Matrix3::from_diagonal(&Vector3::from(eps.map(f64::exp))) * r.transpose()
}

/// Mean evaluations per second of `law` at `kin` from the virgin history.
fn rate(law: &dyn ConstitutiveLaw, kin: &Kinematics) -> (f64, bool) {
    let mut committed = vec![0.0; law.state_len()];
    law.initialise_state(&mut committed);
    let mut trial = committed.clone();
    let mut response = StressResponse::default();
    law.update(kin, &committed, &mut trial, &mut response).expect("benchmark state must be valid");
    let mut out = vec![0.0; law.state_variables().len()];
    law.state_output(&trial, &mut out);
    let plastic = law.state_variables().iter().position(|n| *n == "yield_flag").is_some_and(|i| out[i] == 1.0);
    for _ in 0..1000 {
        law.update(black_box(kin), &committed, &mut trial, &mut response).unwrap();
        black_box(&response);
    }
    let (mut n, start) = (0u64, Instant::now());
    while start.elapsed() < Duration::from_millis(300) {
        for _ in 0..1000 {
            law.update(black_box(kin), &committed, &mut trial, &mut response).unwrap();
            black_box(&response);
        }
        n += 1000;
    }
    (n as f64 / start.elapsed().as_secs_f64(), plastic)
}

fn main() {
    let elastic = |law: &str| json!({"law": law, "density": 2000.0, "young_modulus": 5e7, "poisson_ratio": 0.3});
    let materials = [
        elastic("linear_elastic"),
        elastic("saint_venant_kirchhoff"),
        elastic("neo_hookean"),
        elastic("hencky"),
        json!({"law": "mohr_coulomb", "density": 2000.0, "young_modulus": 5e7, "poisson_ratio": 0.3,
               "friction_angle": 25.0, "cohesion": 5e3, "dilatancy_angle": 5.0}),
        json!({"law": "mohr_coulomb_softening", "density": 2000.0, "young_modulus": 5e7, "poisson_ratio": 0.3,
               "peak_friction_angle": 30.0, "residual_friction_angle": 20.0, "peak_cohesion": 1e4,
               "residual_cohesion": 2e3, "peak_dilatancy_angle": 8.0, "residual_dilatancy_angle": 0.0,
               "shape_factor": 40.0}),
        json!({"law": "drucker_prager", "density": 2000.0, "young_modulus": 5e7, "poisson_ratio": 0.3,
               "friction_angle": 30.0, "cohesion": 5e3, "dilatancy_angle": 10.0, "fit": "plane_strain"}),
        json!({"law": "modified_cam_clay", "density": 1800.0, "preconsolidation_pressure": 2e5, "ocr": 1.2,
               "swelling_slope": 0.02, "compression_slope": 0.1, "critical_state_slope": 1.0,
               "initial_shear_modulus": 2e6, "alpha_shear": 50.0}),
        json!({"law": "newtonian_fluid", "density": 1000.0, "viscosity": 1.0, "bulk_modulus": 2e6}),
        json!({"law": "mu_i", "density": 1500.0, "young_modulus": 5e7, "poisson_ratio": 0.3,
               "static_friction_coefficient": 0.38, "limit_friction_coefficient": 0.64,
               "reference_inertial_number": 0.279, "grain_diameter": 0.5e-3, "grain_density": 2450.0}),
    ];
    println!("| law | state | evaluations/s |");
    println!("|---|---|---:|");
    for m in materials {
        let law = serde_json::from_value::<MaterialSpec>(m).unwrap().build().unwrap();
        let (lambda, mu) = law.elastic_lame();
        let states: Vec<(&str, Matrix3<f64>)> = match law.name() {
            "modified_cam_clay" => {
                vec![("elastic", stretch([-0.0005, 0.0002, 0.0001])), ("plastic", stretch([-0.01, 0.001, 0.002]))]
            }
            "newtonian_fluid" => vec![("viscous", stretch([-0.001, 0.0005, 0.0002]))],
            "mohr_coulomb" | "mohr_coulomb_softening" => vec![
                ("elastic", stretch(hencky_strain(lambda, mu, [-100e3, -120e3, -150e3]))),
                ("plastic (plane)", stretch(hencky_strain(lambda, mu, [-50e3, -200e3, -400e3]))),
                ("plastic (edge)", stretch(hencky_strain(lambda, mu, [-100e3, -100e3, -400e3]))),
            ],
            "drucker_prager" => vec![
                ("elastic", stretch(hencky_strain(lambda, mu, [-100e3, -120e3, -150e3]))),
                ("plastic (cone)", stretch(hencky_strain(lambda, mu, [-50e3, -200e3, -400e3]))),
            ],
            "mu_i" => vec![
                ("elastic", stretch(hencky_strain(lambda, mu, [-100e3, -120e3, -150e3]))),
                ("plastic (flowing)", stretch(hencky_strain(lambda, mu, [-50e3, -200e3, -400e3]))),
            ],
            _ => vec![("elastic", stretch([0.01, -0.02, 0.005]))],
        };
        for (label, f) in states {
            let kin = Kinematics {
                deformation_gradient: f,
                previous_deformation_gradient: Matrix3::identity(),
                time_step: 0.01,
                tangent: TangentRequest::Full,
            };
            let (r, plastic) = rate(law.as_ref(), &kin);
            assert_eq!(plastic, label.starts_with("plastic"), "{} {label}", law.name());
            println!("| {} | {label} | {:.3e} |", law.name(), r);
        }
    }
}
