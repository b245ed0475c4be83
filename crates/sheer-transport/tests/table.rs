//! The precomputed all-orders table: file round trip and validation, exactness at nodes, and its
//! interpolation error against the solver at off-grid points.

use sheer_transport::{AllOrdersTable, SlabSolver, TableFace, TableSpec, TransportError};

fn shipped() -> AllOrdersTable {
    AllOrdersTable::read(AllOrdersTable::DEFAULT_PATH)
        .expect("the shipped table, assets/all_orders_table.bin at the workspace root")
}

#[test]
fn shipped_table_has_default_grid_and_fits_size_budget() {
    let table = shipped();
    assert_eq!(table.spec(), TableSpec::default());
    let bytes = table.to_bytes();
    assert!(bytes.len() < 2 * 1024 * 1024);
    assert_eq!(AllOrdersTable::from_bytes(&bytes).unwrap(), table);
}

#[test]
fn malformed_files_are_rejected() {
    let bytes = shipped().to_bytes();
    let mut bad_magic = bytes.clone();
    bad_magic[0] = b'X';
    assert!(matches!(
        AllOrdersTable::from_bytes(&bad_magic),
        Err(TransportError::TableFormat(_))
    ));
    assert!(matches!(
        AllOrdersTable::from_bytes(&bytes[..bytes.len() - 4]),
        Err(TransportError::TableFormat(_))
    ));
    assert!(matches!(
        AllOrdersTable::from_bytes(&bytes[..20]),
        Err(TransportError::TableFormat(_))
    ));
    let mut not_finite = bytes.clone();
    let last = not_finite.len() - 4;
    not_finite[last..].copy_from_slice(&f32::NAN.to_le_bytes());
    assert!(matches!(
        AllOrdersTable::from_bytes(&not_finite),
        Err(TransportError::TableFormat(_))
    ));
}

/// A header with the given counts and τ1 range, a zero checksum and no values.
fn header_only(counts: [u32; 3], tau_range: (f64, f64)) -> Vec<u8> {
    let mut bytes = b"SHEERAOT".to_vec();
    bytes.extend_from_slice(&2u32.to_le_bytes());
    for count in counts {
        bytes.extend_from_slice(&count.to_le_bytes());
    }
    bytes.extend_from_slice(&tau_range.0.to_le_bytes());
    bytes.extend_from_slice(&tau_range.1.to_le_bytes());
    bytes.extend_from_slice(&0u64.to_le_bytes());
    bytes
}

/// Any one byte changed anywhere in the file, to a value that is still a finite, plausible `ln f`,
/// fails the checksum: a damaged table is refused on load, not sampled.
#[test]
fn a_changed_byte_fails_the_checksum() {
    let bytes = shipped().to_bytes();
    // Offsets in the values (the low byte of an f32 mantissa: still finite) and in the header's τ1 range.
    for offset in [48, 48 + 4 * 1000, bytes.len() - 4, 30] {
        let mut damaged = bytes.clone();
        damaged[offset] ^= 0x01;
        let error = AllOrdersTable::from_bytes(&damaged)
            .unwrap_err()
            .to_string();
        assert!(error.contains("checksum"), "byte {offset}: {error}");
    }
    // The checksum field itself.
    let mut damaged = bytes.clone();
    damaged[40] ^= 0x80;
    let error = AllOrdersTable::from_bytes(&damaged)
        .unwrap_err()
        .to_string();
    assert!(error.contains("checksum"), "{error}");
    // A table written by an older build (version 1, no checksum) is refused with the remedy.
    let mut old = bytes.clone();
    old[8..12].copy_from_slice(&1u32.to_le_bytes());
    let error = AllOrdersTable::from_bytes(&old).unwrap_err().to_string();
    assert!(
        error.contains("version 1") && error.contains("make_table"),
        "{error}"
    );
}

#[test]
fn header_with_wrapping_counts_is_rejected() {
    // 2 · 2 · (2^31)² · 2 sides wraps to 0 values in 64-bit arithmetic: a header-only file must not parse.
    let bytes = header_only([2, 2, 1 << 31], (0.01, 10.0));
    assert!(matches!(
        AllOrdersTable::from_bytes(&bytes),
        Err(TransportError::TableFormat(_))
    ));
}

#[test]
fn huge_tau_range_is_rejected() {
    // τ1 = 1e300 makes the albedo warp e^β − 1 infinite; the range must be refused up front.
    let table = shipped();
    let mut bytes = table.to_bytes();
    bytes[32..40].copy_from_slice(&1.0e300f64.to_le_bytes());
    assert!(matches!(
        AllOrdersTable::from_bytes(&bytes),
        Err(TransportError::TableFormat(_))
    ));
    let spec = TableSpec {
        tau_max: 1.0e300,
        ..TableSpec::default()
    };
    assert!(matches!(
        AllOrdersTable::generate(spec),
        Err(TransportError::TableFormat(_))
    ));
}

#[test]
fn table_reproduces_solver_at_nodes() {
    // At nodes only storage rounding remains: ln f in f32 with |ln f| < 16 carries an absolute error
    // below 16 × 2^-24 ≈ 1e-6, i.e. a relative error of 1e-6 on the multiple part; the solver itself
    // is repeatable exactly. Tolerance 2e-6.
    let table = shipped();
    let spec = table.spec();
    for t in [0usize, 17, 48] {
        let tau1 = spec.tau_at(t as f64);
        for a in [0usize, 3, 12] {
            let albedo = spec.albedo_at(a as f64, tau1);
            let solution = SlabSolver::new(tau1, albedo).unwrap();
            for k in [2usize, 14] {
                let mu0 = spec.cosine_at(k as f64);
                let s = solution.solve(mu0).unwrap();
                for j in [0usize, 5, 14] {
                    let mu = spec.cosine_at(j as f64);
                    let exact = s.multiple_reflected_radiance(mu).unwrap();
                    let ours = table
                        .multiple_reflected_radiance(tau1, albedo, mu0, mu)
                        .unwrap();
                    assert!(
                        ((ours - exact) / exact).abs() < 2e-6,
                        "{tau1} {albedo} {mu0} {mu}"
                    );
                    let exact = s.multiple_transmitted_radiance(mu).unwrap();
                    let ours = table
                        .multiple_transmitted_radiance(tau1, albedo, mu0, mu)
                        .unwrap();
                    assert!(
                        ((ours - exact) / exact).abs() < 2e-6,
                        "{tau1} {albedo} {mu0} {mu}"
                    );
                }
            }
        }
    }
}

#[test]
fn interpolation_error_against_solver_is_within_stated_bounds() {
    // Points halfway between nodes on all four axes at once (the worst case for multilinear
    // interpolation). This sweep is a subset of the one `make_table` prints (README, "Table"), whose
    // maxima over cosines ≥ 0.05 are 4.4e-3 (reflected) and 3.2e-2 (transmitted) relative error in
    // the all-orders radiance; those maxima therefore bound this subset, rounded up to 5e-3 and 3.5e-2.
    let table = shipped();
    let spec = table.spec();
    let (mut worst_reflected, mut worst_transmitted) = (0.0f64, 0.0f64);
    for t in (0..spec.tau_count - 1).step_by(6) {
        let tau1 = spec.tau_at(t as f64 + 0.5);
        for a in (0..spec.albedo_count - 1).step_by(4) {
            let albedo = spec.albedo_at(a as f64 + 0.5, tau1);
            let solver = SlabSolver::new(tau1, albedo).unwrap();
            for k in (0..spec.cosine_count - 1).step_by(4) {
                let mu0 = spec.cosine_at(k as f64 + 0.5);
                let solution = solver.solve(mu0).unwrap();
                for j in (0..spec.cosine_count - 1).step_by(4) {
                    let mu = spec.cosine_at(j as f64 + 0.5);
                    if mu.min(mu0) < 0.05 {
                        continue;
                    }
                    let exact = solution.reflected_radiance(mu).unwrap();
                    let ours = table.reflected_radiance(tau1, albedo, mu0, mu).unwrap();
                    worst_reflected = worst_reflected.max(((ours - exact) / exact).abs());
                    let exact = solution.transmitted_radiance(mu).unwrap();
                    let ours = table.transmitted_radiance(tau1, albedo, mu0, mu).unwrap();
                    worst_transmitted = worst_transmitted.max(((ours - exact) / exact).abs());
                }
            }
        }
    }
    println!("worst reflected {worst_reflected:.3e}, transmitted {worst_transmitted:.3e}");
    assert!(worst_reflected < 5e-3, "reflected {worst_reflected}");
    assert!(
        worst_transmitted < 3.5e-2,
        "transmitted {worst_transmitted}"
    );
}

#[test]
fn queries_outside_the_table_are_errors_and_zero_albedo_is_single_scattering() {
    let table = shipped();
    assert!(matches!(
        table.reflected_radiance(20.0, 0.9, 0.5, 0.5),
        Err(TransportError::OutsideTable { .. })
    ));
    assert!(matches!(
        table.transmitted_radiance(0.001, 0.9, 0.5, 0.5),
        Err(TransportError::OutsideTable { .. })
    ));
    assert!(matches!(
        table.reflected_radiance(1.0, 1.1, 0.5, 0.5),
        Err(TransportError::Albedo(_))
    ));
    // Λ = 0 scatters nothing; the table's ends τ1 = 0.01 and 10 are accepted.
    assert_eq!(table.reflected_radiance(0.01, 0.0, 0.5, 0.5).unwrap(), 0.0);
    assert!(table.transmitted_radiance(10.0, 1.0, 0.5, 0.5).unwrap() > 0.0);
}

#[test]
fn generation_is_independent_of_thread_count() {
    let spec = TableSpec {
        tau_count: 3,
        tau_min: 0.1,
        tau_max: 1.0,
        albedo_count: 2,
        cosine_count: 3,
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| AllOrdersTable::generate(spec).unwrap())
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn logarithm_and_channel_samplers_agree_with_the_radiance_sampler() {
    // The reduced logarithm is what the radiance sampler exponentiates (L_m = Λ² μ0 e^{ln f}), and the
    // three-channel sampler (shared cosine and τ1 positions, as the renderer's CPU path uses it) gives
    // each channel's one-channel result bit for bit, with equal and with different τ1.
    let table = shipped();
    for (taus, albedos, mu0, mu) in [
        ([2.0, 2.0, 2.0], [1.0, 0.5, 0.03], 0.6, 0.8),
        ([0.01, 3.7, 10.0], [0.9, 0.0, 0.99], 1.0, 0.001),
        ([0.2, 0.2, 7.5], [0.7, 0.7, 0.2], 0.05, 1.0),
    ] {
        for face in [TableFace::Reflected, TableFace::Transmitted] {
            let channels = table
                .log_reduced_multiple_radiance_channels(face, taus, albedos, mu0, mu)
                .unwrap();
            for c in 0..3 {
                let one = table
                    .log_reduced_multiple_radiance(face, taus[c], albedos[c], mu0, mu)
                    .unwrap();
                assert_eq!(channels[c].to_bits(), one.to_bits(), "{face:?} {c}");
                let radiance = match face {
                    TableFace::Reflected => {
                        table.multiple_reflected_radiance(taus[c], albedos[c], mu0, mu)
                    }
                    TableFace::Transmitted => {
                        table.multiple_transmitted_radiance(taus[c], albedos[c], mu0, mu)
                    }
                }
                .unwrap();
                assert_eq!(radiance, albedos[c] * albedos[c] * mu0 * one.exp());
            }
        }
    }
    // Any channel outside the table is an error.
    assert!(matches!(
        table.log_reduced_multiple_radiance_channels(
            TableFace::Reflected,
            [2.0, 11.0, 2.0],
            [0.5; 3],
            0.5,
            0.5
        ),
        Err(TransportError::OutsideTable { value, .. }) if value == 11.0
    ));
}
