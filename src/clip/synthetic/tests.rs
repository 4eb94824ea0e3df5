//! Tests of the synthetic clip: geometry, convergence order, determinism, errors, scoring.
use super::*;

/// Synthetic kymogram: a travelling bending wave with a slowly growing offset, `rows × 24`.
fn wave_rows(rows: usize) -> Vec<Vec<f64>> {
    (0..rows)
        .map(|n| {
            let t = n as f64 / rows as f64;
            (0..24).map(|j| 0.05 + 0.1 * t + 0.3 * (2.0 * PI * (j as f64 / 24.0 - 2.0 * t)).sin()).collect()
        })
        .collect()
}

fn small(frames: usize) -> RollClipParams {
    RollClipParams { frames, ..RollClipParams::default() }
}

fn row(q: &Matrix3<f64>, i: usize) -> Vector3<f64> {
    q.row(i).transpose()
}

#[test]
fn frames_are_orthonormal_and_proper() {
    let (clip, truth) = roll_clip(&wave_rows(40), None, &small(9)).unwrap();
    assert_eq!((clip.frame_count(), clip.node_count(), truth.frames.len()), (9, 128, 9));
    let mut worst: f64 = 0.0;
    for q in truth.frames.iter().flat_map(|f| &f.q) {
        worst = worst.max((q * q.transpose() - Matrix3::identity()).amax()).max((q.determinant() - 1.0).abs());
    }
    println!("max |QQᵀ − I|, |det Q − 1|: {worst:.2e}");
    assert!(worst < 1e-13, "{worst:e}");
    assert!(clip.frames.iter().all(|f| f[0] == Vector3::zeros()));
    assert!(truth.frames.iter().all(|f| f.q[0] == Matrix3::identity()));
}

/// `∂s x = d3` and `κˡ = Q κᵍ`, `κᵍ = ½ Σ d_i × ∂s d_i` (eqs. (19), (4)) by central
/// differences on a fine node grid reproduce the prescribed field.
#[test]
fn finite_differences_of_the_frames_give_the_prescribed_curvature() {
    let nodes = 2001;
    let params = RollClipParams {
        nodes,
        frames: 3,
        substeps: 2,
        roll_total_rad: 1.1,
        twist_per_m: 700.0,
        ..RollClipParams::default()
    };
    let (clip, truth) = roll_clip(&wave_rows(30), None, &params).unwrap();
    let h = params.length_m / (nodes - 1) as f64;
    let (mut tangent_err, mut kappa_err, mut kappa_max): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for (x, t) in clip.frames.iter().zip(&truth.frames) {
        for i in 1..nodes - 1 {
            let dx = (x[i + 1] - x[i - 1]) / (2.0 * h);
            tangent_err = tangent_err.max((dx - row(&t.q[i], 2)).norm());
            let dq = (t.q[i + 1] - t.q[i - 1]) / (2.0 * h);
            let kappa_g: Vector3<f64> = (0..3).map(|k| row(&t.q[i], k).cross(&row(&dq, k)) * 0.5).sum();
            let kappa_l = t.q[i] * kappa_g;
            kappa_err = kappa_err.max((kappa_l - t.kappa[i]).amax());
            kappa_max = kappa_max.max(t.kappa[i].amax());
        }
    }
    println!("FD: max |∂s x − d3| {tangent_err:.2e}, max |κˡ_FD − κˡ| {kappa_err:.2e} 1/m of max {kappa_max:.1} 1/m");
    // Central differences are second order: error ~ h² (κ² + κ'') / 6 ≈ 1e-6 here.
    assert!(tangent_err < 1e-5, "{tangent_err:e}");
    assert!(kappa_err < 1e-4 * kappa_max, "{kappa_err:e}");
}

/// Fourth order: errors against a 64-substep reference fall ~16× per doubling.
#[test]
fn integration_converges_at_fourth_order() {
    let rows = wave_rows(20);
    let run = |substeps| {
        roll_clip(
            &rows,
            None,
            &RollClipParams { frames: 3, substeps, roll_total_rad: 1.0, ..RollClipParams::default() },
        )
        .unwrap()
    };
    let (reference, reference_truth) = run(64);
    let err = |substeps| {
        let (clip, truth) = run(substeps);
        let ex = clip
            .frames
            .iter()
            .flatten()
            .zip(reference.frames.iter().flatten())
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        let eq = truth
            .frames
            .iter()
            .flat_map(|f| &f.q)
            .zip(reference_truth.frames.iter().flat_map(|f| &f.q))
            .map(|(a, b)| (a - b).amax())
            .fold(0.0, f64::max);
        (ex / WORM_LENGTH_M, eq)
    };
    let e: Vec<(f64, f64)> = [1, 2, 4, 8].into_iter().map(err).collect();
    for (k, ((x0, q0), (x1, q1))) in e.iter().zip(&e[1..]).enumerate() {
        println!("substeps {} → {}: max |Δx|/L {x0:.2e} → {x1:.2e} (ratio {:.2}), max |ΔQ| {q0:.2e} → {q1:.2e} (ratio {:.2})", 1 << k, 2 << k, x0 / x1, q0 / q1);
        assert!((12.0..20.0).contains(&(x0 / x1)), "position ratio {}", x0 / x1);
        assert!((12.0..20.0).contains(&(q0 / q1)), "frame ratio {}", q0 / q1);
    }
    let default = err(RollClipParams::default().substeps);
    println!(
        "default substeps {}: max |Δx|/L {:.2e}, max |ΔQ| {:.2e}",
        RollClipParams::default().substeps,
        default.0,
        default.1
    );
    assert!(default.0 < 1e-10 && default.1 < 1e-9, "{default:?}");
}

/// ψ = 0, τ = 0: bending about d2 only, so y ≡ 0 and d2 ≡ e2; the tangent's turning angle
/// is `∫ k ds` (at the knots, every 5th node with 126 nodes).
#[test]
fn planar_case_lies_in_the_xz_plane_and_turns_by_the_integral_of_k() {
    let params =
        RollClipParams { nodes: 126, frames: 4, roll_total_rad: 0.0, twist_per_m: 0.0, ..RollClipParams::default() };
    let rows = wave_rows(12);
    let (clip, truth) = roll_clip(&rows, None, &params).unwrap();
    let field = KymogramField::new(&rows, None, &params).unwrap();
    let mut worst: f64 = 0.0;
    for (n, (x, t)) in clip.frames.iter().zip(&truth.frames).enumerate() {
        assert!(x.iter().all(|p| p.y == 0.0), "frame {n}: y ≠ 0");
        assert!(t.q.iter().all(|q| row(q, 1) == Vector3::y()), "frame {n}: d2 ≠ e2");
        let profile = field.profile(field.row_at_frame(n));
        // Unwrapped tangent angle from +e3 towards +e1.
        let (mut theta, mut prev) = (0.0, Vector3::z());
        for (i, q) in t.q.iter().enumerate() {
            let d3 = row(q, 2);
            theta += prev.cross(&d3).y.atan2(prev.dot(&d3));
            prev = d3;
            if i % 5 == 0 {
                let knot = BendingProfile {
                    k: profile.k[..=i / 5].to_vec(),
                    m: profile.m[..=i / 5].to_vec(),
                    segment_m: profile.segment_m,
                };
                worst = worst.max((theta - knot.integral()).abs());
            }
        }
        assert!((theta - profile.integral()).abs() < 1e-11, "frame {n}: {theta} vs {}", profile.integral());
    }
    println!("planar: max |θ(s_knot) − ∫k ds| {worst:.2e} rad");
    assert!(worst < 1e-11, "{worst:e}");
    // Rolled by π/2 (bending about −d1): the last frame lies in the y–z plane, d1 = e1.
    let rolled = RollClipParams { roll_total_rad: PI / 2.0, ..params };
    let (clip, truth) = roll_clip(&rows, None, &rolled).unwrap();
    let last = clip.frames.len() - 1;
    let off_plane = clip.frames[last].iter().map(|p| p.x.abs()).fold(0.0, f64::max);
    assert!(off_plane < 1e-15 * rolled.length_m, "{off_plane:e}");
    assert!(truth.frames[last].q.iter().all(|q| (row(q, 0) - Vector3::x()).amax() < 1e-14));
    assert!(clip.frames[last].iter().any(|p| p.y.abs() > 0.1 * rolled.length_m), "bent in y");
}

/// Clip frames that fall on kymogram rows reproduce them; joints carry `a_j (M + 1)/L`.
#[test]
fn time_and_space_splines_interpolate_the_kymogram() {
    let rows = wave_rows(25);
    let params = small(2 * 25 - 1);
    let field = KymogramField::new(&rows, None, &params).unwrap();
    let segment = params.length_m / 25.0;
    let mut worst: f64 = 0.0;
    for (r, row) in rows.iter().enumerate() {
        assert_eq!(field.row_at_frame(2 * r), r as f64);
        let angles = field.joint_angles(field.row_at_frame(2 * r));
        let profile = field.profile(r as f64);
        for j in 0..24 {
            worst = worst
                .max((angles[j] - row[j]).abs())
                .max((profile.at((j + 1) as f64 * segment) * segment - row[j]).abs());
        }
        assert_eq!((profile.at(0.0), profile.at(params.length_m)), (0.0, 0.0), "k = 0 at head and tail");
    }
    assert!(worst < 1e-13, "{worst:e}");
    // Between rows the spline is smooth: the half-row value is near the linear mean.
    let mid = field.joint_angles(10.5);
    assert!((mid[3] - 0.5 * (rows[10][3] + rows[11][3])).abs() < 0.01);
    // Omega then delta plays both, stretched together.
    let both = KymogramField::new(
        &rows,
        Some(&wave_rows(7)),
        &RollClipParams { time_mapping: TimeMapping::OmegaThenDelta, ..small(32) },
    )
    .unwrap();
    assert_eq!(both.row_count(), 32);
    assert_eq!(both.joint_angles(both.row_at_frame(31)), wave_rows(7)[6]);
    // Roll: 0 at the start, ψ_tot at the end, zero rate at both ends.
    let p = small(101);
    assert_eq!(p.roll_at_frame(0), 0.0);
    assert!((p.roll_at_frame(100) - PI / 2.0).abs() < 1e-15);
    assert!(p.roll_at_frame(1) < 1e-3 && (p.roll_at_frame(50) - PI / 4.0).abs() < 1e-15);
}

#[test]
fn output_is_deterministic() {
    let rows = wave_rows(15);
    let params = small(5);
    let (c1, t1) = roll_clip(&rows, None, &params).unwrap();
    let (c2, t2) = roll_clip(&rows, None, &params).unwrap();
    let bits = |c: &Clip| {
        c.frames.iter().flatten().flat_map(|p| p.iter().map(|v| v.to_bits()).collect::<Vec<_>>()).collect::<Vec<u64>>()
    };
    let qbits = |t: &GroundTruth| {
        t.frames
            .iter()
            .flat_map(|f| f.q.iter())
            .flat_map(|q| q.iter().map(|v| v.to_bits()).collect::<Vec<_>>())
            .collect::<Vec<u64>>()
    };
    assert_eq!(bits(&c1), bits(&c2));
    assert_eq!(qbits(&t1), qbits(&t2));
    assert_eq!((c1, t1), (c2, t2));
}

#[test]
fn bad_input_gives_clear_errors() {
    let rows = wave_rows(10);
    let e = |r: Result<(Clip, GroundTruth), ClipError>| r.unwrap_err().to_string();
    let p = small(3);
    assert!(e(roll_clip(&[], None, &p)).contains("omega has 0 frames, need at least 2"));
    assert!(e(roll_clip(&rows[..1], None, &p)).contains("omega has 1 frames"));
    assert!(e(roll_clip(&[vec![], vec![]], None, &p)).contains("frame 0: 0 joint angles"));
    let mut ragged = rows.clone();
    ragged[4].pop();
    assert!(e(roll_clip(&ragged, None, &p)).contains("omega, frame 4: 23 joint angles, but frame 0 has 24"));
    let mut nan = rows.clone();
    nan[6][2] = f64::NAN;
    assert!(e(roll_clip(&nan, None, &p)).contains("omega, frame 6, joint 2: angle NaN is not finite"));
    let both = RollClipParams { time_mapping: TimeMapping::OmegaThenDelta, ..p.clone() };
    assert!(e(roll_clip(&rows, None, &both)).contains("needs the delta-turn kymogram"));
    let short: Vec<Vec<f64>> = rows.iter().map(|r| r[..20].to_vec()).collect();
    assert!(e(roll_clip(&rows, Some(&short), &both)).contains("delta, frame 0: 20 joint angles, but frame 0 has 24"));
    // Delta rows are ignored by the omega-only mapping.
    assert!(roll_clip(&rows, Some(&short), &p).is_ok());
    for (params, name) in [
        (RollClipParams { length_m: 0.0, ..p.clone() }, "length_m = 0"),
        (RollClipParams { length_m: f64::NAN, ..p.clone() }, "length_m = NaN"),
        (RollClipParams { nodes: 1, ..p.clone() }, "nodes = 1"),
        (RollClipParams { frames: 0, ..p.clone() }, "frames = 0"),
        (RollClipParams { dt_s: -0.04, ..p.clone() }, "dt_s = -0.04"),
        (RollClipParams { roll_total_rad: f64::INFINITY, ..p.clone() }, "roll_total_rad = inf"),
        (RollClipParams { twist_per_m: f64::NAN, ..p.clone() }, "twist_per_m = NaN"),
        (RollClipParams { substeps: 0, ..p.clone() }, "substeps = 0"),
    ] {
        let msg = e(roll_clip(&rows, None, &params));
        assert!(msg.contains(name), "expected `{name}` in: {msg}");
    }
    // One frame is allowed: the first kymogram row, no roll.
    let (clip, truth) = roll_clip(&rows, None, &small(1)).unwrap();
    assert_eq!((clip.frame_count(), truth.frames[0].roll_rad), (1, 0.0));
}

#[test]
fn comparison_of_the_truth_with_itself_and_with_a_rolled_copy() {
    let (clip, truth) = roll_clip(&wave_rows(10), None, &small(3)).unwrap();
    let (x, t) = (&clip.frames[1], &truth.frames[1]);
    let same = compare_frame(x, t, &RecoveredFrame { x, q: &t.q, kappa: &t.kappa }, 3).unwrap();
    assert_eq!(
        (same.position_rel_l2, same.bending_rel_l2, same.max_tangent_angle_rad, same.roll_offset_rad),
        (0.0, 0.0, 0.0, 0.0)
    );
    assert_eq!(same.twist_rms_error_per_m, 0.0);
    assert!((same.twist_mean_per_m - 500.0).abs() < 1e-9);
    // Roll every frame by φ about its own d3: rows d1, d2 rotate, κˡ rotates about e3.
    for phi in [0.3, -2.0, PI] {
        let r = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), phi).into_inner();
        let q: Vec<Matrix3<f64>> = t.q.iter().map(|q| r.transpose() * q).collect();
        assert!((row(&q[5], 0) - (row(&t.q[5], 0) * phi.cos() + row(&t.q[5], 1) * phi.sin())).amax() < 1e-15);
        let kappa: Vec<Vector3<f64>> = t.kappa.iter().map(|k| r.transpose() * k).collect();
        let c = compare_frame(x, t, &RecoveredFrame { x, q: &q, kappa: &kappa }, 0).unwrap();
        assert!((c.roll_offset_rad - phi).abs() < 1e-12, "φ = {phi}: {}", c.roll_offset_rad);
        assert!(c.max_tangent_angle_rad < 1e-15 && c.bending_rel_l2 < 1e-14, "{c:?}");
    }
    // Shifted positions, tilted tangents, doubled twist.
    let shifted: Vec<Vector3<f64>> = x.iter().map(|p| p * 1.01).collect();
    let tilt = nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), 0.1).into_inner();
    let q: Vec<Matrix3<f64>> = t.q.iter().map(|q| q * tilt).collect();
    let kappa: Vec<Vector3<f64>> = t.kappa.iter().map(|k| Vector3::new(k.x * 2.0, k.y * 2.0, 2.0 * k.z)).collect();
    let c = compare_frame(x, t, &RecoveredFrame { x: &shifted, q: &q, kappa: &kappa }, 2).unwrap();
    assert!((c.position_rel_l2 - 0.01).abs() < 1e-12);
    assert!((c.bending_rel_l2 - 3.0).abs() < 1e-12, "b → 4b");
    assert!((c.max_tangent_angle_rad - 0.1).abs() < 1e-12);
    assert!((c.twist_mean_per_m - 1000.0).abs() < 1e-9 && (c.twist_rms_error_per_m - 500.0).abs() < 1e-9);
    // Size mismatches and too many skipped nodes are errors.
    let e = compare_frame(x, t, &RecoveredFrame { x: &x[1..], q: &t.q, kappa: &t.kappa }, 0).unwrap_err().to_string();
    assert!(e.contains("recovered x has 127 nodes, truth has 128"), "{e}");
    let e = compare_frame(x, t, &RecoveredFrame { x, q: &t.q, kappa: &t.kappa }, 64).unwrap_err().to_string();
    assert!(e.contains("skipping 64 nodes at each end of 128"), "{e}");
}
