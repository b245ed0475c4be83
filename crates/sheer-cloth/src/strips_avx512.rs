//! A grid's strips with AVX-512, eight constraints per vector, without gathers and without scalar
//! remainders.
//!
//! An along strip pairs particles within one row: stretch joins `2m` and `2m + 1`, bending `4m + j` and
//! `4m + j + 2`. Left to the vectoriser, the loop over such pairs reads and writes each component of
//! each end with a gather and a scatter (`objdump` of the two AVX-512 loops: 84 gathers, 60 scatters),
//! and the along strips took 31 % of the default flag's frame for a third of its constraints
//! (`perf record -e cpu-clock` of `fingerprint time 64x46 1 800`: 30.9 % along against 24.9 % for the
//! twice as many constraints of the apart strips). Here a block of 16 particles (eight constraints) is
//! loaded as six plain vectors, split into x, y and z of each half of the block by two-source permutes
//! (as the vectoriser does for an apart strip), and the ends of the eight constraints picked out of those
//! by one more permute per component; the results go back the same way. A strip's last, partial block
//! uses masked loads and stores, which touch nothing past the strip.
//!
//! An apart strip's whole blocks vectorise well on their own; its last few constraints (seven of the 63
//! of every shear strip of the default flag) went through the loop's scalar remainder, and go here as one
//! masked block instead ([`project_apart_partial`]).
//!
//! The arithmetic ([`solve`]) is that of [`project`](crate::grid_constraints::project), operation for
//! operation and without fused multiply–adds, so the results are the same bits (tested against it and
//! against the loops in `strip_loops_match_the_one_constraint_projection_bit_for_bit`,
//! `along_strips_of_every_length_match_the_loop_and_touch_nothing_beyond` and
//! `apart_strips_of_every_length_match_the_projection_and_touch_nothing_beyond`; the simulator's
//! fingerprint is unchanged).

use std::arch::x86_64::*;

use glam::DVec3;

use crate::grid_constraints::FamilyConstants;

/// Constraints per block: one vector of eight `f64`.
pub(crate) const BLOCK: usize = 8;

/// Index vectors of `_mm512_permutex2var_pd`, which picks lane `i` of its result from lane `idx[i]` of
/// the sixteen lanes of its two sources (the first's 0–7, the second's 8–15).
type Index = [i64; 8];

/// Component `c` of eight particles stored as 24 consecutive `f64` in three vectors: the first permute
/// takes the lanes that lie in the first two vectors, the second keeps those and adds the rest from the
/// third.
const fn split_components(c: usize) -> (Index, Index) {
    let (mut first, mut second) = ([0; 8], [0; 8]);
    let mut particle = 0;
    while particle < 8 {
        let at = 3 * particle + c;
        if at < 16 {
            first[particle] = at as i64;
            second[particle] = particle as i64;
        } else {
            second[particle] = (8 + at - 16) as i64;
        }
        particle += 1;
    }
    (first, second)
}

/// The inverse of [`split_components`]: output vector `v` (doubles `8v..8v + 8` of the 24) from the
/// x and y vectors by the first permute, then z by the second.
const fn merge_components(v: usize) -> (Index, Index) {
    let (mut first, mut second) = ([0; 8], [0; 8]);
    let mut lane = 0;
    while lane < 8 {
        let at = 8 * v + lane;
        let (particle, c) = (at / 3, at % 3);
        match c {
            0 => first[lane] = particle as i64,
            1 => first[lane] = (8 + particle) as i64,
            _ => {}
        }
        second[lane] = if c == 2 {
            (8 + particle) as i64
        } else {
            lane as i64
        };
        lane += 1;
    }
    (first, second)
}

/// The first end of constraint `l` of a block, among its 16 particles.
const fn first_end(half: usize, l: usize) -> usize {
    2 * half * (l / half) + l % half
}

/// Lanes of the first and second ends of the eight constraints, from particles 0–7 and 8–15.
const fn split_ends(half: usize) -> (Index, Index) {
    let (mut a, mut b) = ([0; 8], [0; 8]);
    let mut l = 0;
    while l < 8 {
        a[l] = first_end(half, l) as i64;
        b[l] = (first_end(half, l) + half) as i64;
        l += 1;
    }
    (a, b)
}

/// The inverse of [`split_ends`]: particles `8h..8h + 8` from the first ends (lanes 0–7) and the
/// second (8–15).
const fn merge_ends(half: usize, h: usize) -> Index {
    let mut index = [0; 8];
    let mut l = 0;
    while l < 8 {
        let a = first_end(half, l);
        let b = a + half;
        if a / 8 == h {
            index[a % 8] = l as i64;
        }
        if b / 8 == h {
            index[b % 8] = (8 + l) as i64;
        }
        l += 1;
    }
    index
}

const SPLIT: [(Index, Index); 3] = [
    split_components(0),
    split_components(1),
    split_components(2),
];
const MERGE: [(Index, Index); 3] = [
    merge_components(0),
    merge_components(1),
    merge_components(2),
];

/// The constant tables of one strip layout.
struct Tables {
    split_ends: (Index, Index),
    merge_ends: [Index; 2],
}

const TABLES: [Tables; 2] = [
    Tables {
        split_ends: split_ends(1),
        merge_ends: [merge_ends(1, 0), merge_ends(1, 1)],
    },
    Tables {
        split_ends: split_ends(2),
        merge_ends: [merge_ends(2, 0), merge_ends(2, 1)],
    },
];

#[target_feature(enable = "avx512f")]
#[inline]
fn index(index: &Index) -> __m512i {
    // SAFETY: an `Index` is 64 readable bytes.
    unsafe { _mm512_loadu_si512(index.as_ptr().cast()) }
}

/// The lanes of vector `k` (`f64` `8k..8k + 8`) among the first `count` `f64`.
fn lanes(count: usize, k: usize) -> __mmask8 {
    let valid = count.saturating_sub(8 * k).min(8);
    ((1u32 << valid) - 1) as __mmask8
}

/// Vector `k` of the first `count` `f64` at `p`, zero beyond them; nothing past them is read (a masked
/// load does not touch its masked-out lanes, and a vector wholly past them is not loaded).
///
/// # Safety
/// `count` `f64` readable at `p`.
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn load<const PARTIAL: bool>(p: *const f64, count: usize, k: usize) -> __m512d {
    if !PARTIAL {
        // SAFETY: a whole block: all eight lanes lie within the first `count`.
        return unsafe { _mm512_loadu_pd(p.add(8 * k)) };
    }
    let mask = lanes(count, k);
    if mask == 0 {
        return _mm512_setzero_pd();
    }
    // SAFETY: lane `i` of the mask is set only for `8k + i < count`.
    unsafe { _mm512_maskz_loadu_pd(mask, p.add(8 * k)) }
}

/// Stores vector `k` of the first `count` `f64` at `p`, nothing past them.
///
/// # Safety
/// `count` `f64` writable at `p`.
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn store<const PARTIAL: bool>(p: *mut f64, count: usize, k: usize, v: __m512d) {
    if !PARTIAL {
        // SAFETY: a whole block: all eight lanes lie within the first `count`.
        unsafe { _mm512_storeu_pd(p.add(8 * k), v) };
        return;
    }
    let mask = lanes(count, k);
    if mask != 0 {
        // SAFETY: lane `i` of the mask is set only for `8k + i < count`.
        unsafe { _mm512_mask_storeu_pd(p.add(8 * k), mask, v) }
    }
}

/// x, y and z of the first `particles` (at most 16) of the 16 particles at `p`, each as the eight first
/// ends then the eight second ends of the block's constraints; lanes past them are zero.
///
/// # Safety
/// `3 · particles` `f64` readable at `p`.
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn load_ends<const PARTIAL: bool>(
    p: *const f64,
    particles: usize,
    tables: &Tables,
) -> [[__m512d; 2]; 3] {
    // SAFETY: `load` reads only the first `3 · particles` `f64`.
    unsafe {
        let r: [__m512d; 6] = std::array::from_fn(|k| load::<PARTIAL>(p, 3 * particles, k));
        let (a, b) = (index(&tables.split_ends.0), index(&tables.split_ends.1));
        std::array::from_fn(|c| {
            let (first, second) = (index(&SPLIT[c].0), index(&SPLIT[c].1));
            let low =
                _mm512_permutex2var_pd(_mm512_permutex2var_pd(r[0], first, r[1]), second, r[2]);
            let high =
                _mm512_permutex2var_pd(_mm512_permutex2var_pd(r[3], first, r[4]), second, r[5]);
            [
                _mm512_permutex2var_pd(low, a, high),
                _mm512_permutex2var_pd(low, b, high),
            ]
        })
    }
}

/// Writes what [`load_ends`] read back to the first `particles` particles at `p`.
///
/// # Safety
/// `3 · particles` `f64` writable at `p`.
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn store_ends<const PARTIAL: bool>(
    p: *mut f64,
    particles: usize,
    ends: [[__m512d; 2]; 3],
    tables: &Tables,
) {
    // SAFETY: `store` writes only the first `3 · particles` `f64`.
    unsafe {
        let (low, high) = (index(&tables.merge_ends[0]), index(&tables.merge_ends[1]));
        // Particles 0–7 and 8–15, each as x, y and z.
        let halves: [[__m512d; 3]; 2] = [low, high].map(|half| {
            std::array::from_fn(|c| _mm512_permutex2var_pd(ends[c][0], half, ends[c][1]))
        });
        for (h, [x, y, z]) in halves.into_iter().enumerate() {
            for (v, merge) in MERGE.iter().enumerate() {
                let xy = _mm512_permutex2var_pd(x, index(&merge.0), y);
                let xyz = _mm512_permutex2var_pd(xy, index(&merge.1), z);
                store::<PARTIAL>(p, 3 * particles, 3 * h + v, xyz);
            }
        }
    }
}

/// Negation by the sign bit, as Rust's unary minus (`0 − x` would turn −0 into +0).
#[target_feature(enable = "avx512f")]
#[inline]
fn negate(x: __m512d) -> __m512d {
    _mm512_castsi512_pd(_mm512_xor_si512(
        _mm512_castpd_si512(x),
        _mm512_set1_epi64(i64::MIN),
    ))
}

/// `(x0·x1 + y0·y1) + z0·z1`, in glam's order.
#[target_feature(enable = "avx512f")]
#[inline]
fn dot(a: [__m512d; 3], b: [__m512d; 3]) -> __m512d {
    _mm512_add_pd(
        _mm512_add_pd(_mm512_mul_pd(a[0], b[0]), _mm512_mul_pd(a[1], b[1])),
        _mm512_mul_pd(a[2], b[2]),
    )
}

/// Projects an along strip of `HALF` constraints per chunk of `2·HALF` particles (see
/// `grid_constraints::project_along`), eight constraints at a time; the last block may be partial (its
/// missing lanes are loaded as zeros, which make an inactive constraint, and not stored). The slices are
/// those `project_along` takes, flattened: `x`, `previous` and `inverse_masses` per particle, the rest per
/// constraint.
///
/// # Safety
/// The CPU must have AVX-512F.
#[target_feature(enable = "avx512f")]
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn project_along<
    const PBD: bool,
    const MULTIPLIERS: bool,
    const DAMPED: bool,
    const HALF: usize,
>(
    x: &mut [DVec3],
    previous: &[DVec3],
    inverse_masses: &[f64],
    rest_lengths: &[f64],
    inverse_denominators: &[f64],
    lambdas: &mut [f64],
    family: FamilyConstants,
) {
    const {
        assert!(
            HALF == 1 || HALF == 2,
            "along strips pair neighbours 1 or 2 apart"
        )
    };
    let constraints = rest_lengths.len();
    assert!(
        x.len() == 2 * constraints && previous.len() == x.len() && inverse_masses.len() == x.len()
    );
    assert!(inverse_denominators.len() == constraints && lambdas.len() == constraints);
    let whole = constraints / BLOCK * BLOCK;
    for first in (0..whole).step_by(BLOCK) {
        // SAFETY: the asserts above make the block's particles and constraints valid.
        unsafe {
            block::<PBD, MULTIPLIERS, DAMPED, HALF, false>(
                x,
                previous,
                inverse_masses,
                rest_lengths,
                inverse_denominators,
                lambdas,
                family,
                first,
                BLOCK,
            )
        };
    }
    if whole < constraints {
        // SAFETY: as above, for the `constraints − whole` left.
        unsafe {
            block::<PBD, MULTIPLIERS, DAMPED, HALF, true>(
                x,
                previous,
                inverse_masses,
                rest_lengths,
                inverse_denominators,
                lambdas,
                family,
                whole,
                constraints - whole,
            )
        };
    }
}

/// Projects constraints `first..first + count` (`count` ≤ 8; below 8 only with `PARTIAL`) of
/// [`project`]'s strip.
///
/// # Safety
/// The slices as `project` asserts them, and `first + count` at most the constraint count.
#[target_feature(enable = "avx512f")]
#[inline]
#[allow(clippy::too_many_arguments)]
unsafe fn block<
    const PBD: bool,
    const MULTIPLIERS: bool,
    const DAMPED: bool,
    const HALF: usize,
    const PARTIAL: bool,
>(
    x: &mut [DVec3],
    previous: &[DVec3],
    inverse_masses: &[f64],
    rest_lengths: &[f64],
    inverse_denominators: &[f64],
    lambdas: &mut [f64],
    family: FamilyConstants,
    first: usize,
    count: usize,
) {
    let tables = &TABLES[HALF - 1];
    let (split_a, split_b) = (index(&tables.split_ends.0), index(&tables.split_ends.1));
    let particles = 2 * count;
    // SAFETY (the loads and stores below): by the caller's contract, `particles` particles and `count`
    // constraints from the block's first are valid; `DVec3` is three `f64` (`repr(C)`).
    unsafe {
        let x_at = x.as_mut_ptr().add(2 * first).cast::<f64>();
        let [[ax, bx], [ay, by], [az, bz]] = load_ends::<PARTIAL>(x_at, particles, tables);
        let w = inverse_masses.as_ptr().add(2 * first);
        let (w_low, w_high) = (
            load::<PARTIAL>(w, particles, 0),
            load::<PARTIAL>(w, particles, 1),
        );
        let w_a = _mm512_permutex2var_pd(w_low, split_a, w_high);
        let w_b = _mm512_permutex2var_pd(w_low, split_b, w_high);
        let previous_ends = if DAMPED {
            let previous_at = previous.as_ptr().add(2 * first).cast::<f64>();
            let [[pax, pbx], [pay, pby], [paz, pbz]] =
                load_ends::<PARTIAL>(previous_at, particles, tables);
            [[pax, pay, paz], [pbx, pby, pbz]]
        } else {
            [[_mm512_setzero_pd(); 3]; 2]
        };
        let constraints = Constraints {
            rest: load::<PARTIAL>(rest_lengths.as_ptr().add(first), count, 0),
            inverse_denominator: load::<PARTIAL>(
                inverse_denominators.as_ptr().add(first),
                count,
                0,
            ),
            lambdas: lambdas.as_mut_ptr().add(first),
            count,
        };
        let [[ax, ay, az], [bx, by, bz]] = solve::<PBD, MULTIPLIERS, DAMPED, PARTIAL>(
            [[ax, ay, az], [bx, by, bz]],
            previous_ends,
            [w_a, w_b],
            constraints,
            family,
        );
        store_ends::<PARTIAL>(x_at, particles, [[ax, bx], [ay, by], [az, bz]], tables);
    }
}

/// A block's per-constraint data: rest lengths and inverted divisors (zero past `count`), and where
/// its `count` multipliers are.
struct Constraints {
    rest: __m512d,
    inverse_denominator: __m512d,
    lambdas: *mut f64,
    count: usize,
}

/// The arithmetic of [`project`](crate::grid_constraints::project) on eight constraints at once: the
/// ends `[a, b]` (x, y and z each), their start positions (read only when `DAMPED`) and inverse masses;
/// returns the ends moved. Operation for operation the scalar function's, without fused multiply–adds.
///
/// # Safety
/// With `MULTIPLIERS`, `constraints.count` multipliers readable and writable at `constraints.lambdas`.
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn solve<
    const PBD: bool,
    const MULTIPLIERS: bool,
    const DAMPED: bool,
    const PARTIAL: bool,
>(
    [a, b]: [[__m512d; 3]; 2],
    [previous_a, previous_b]: [[__m512d; 3]; 2],
    [w_a, w_b]: [__m512d; 2],
    constraints: Constraints,
    family: FamilyConstants,
) -> [[__m512d; 3]; 2] {
    let Constraints {
        rest,
        inverse_denominator,
        lambdas: lambda_at,
        count,
    } = constraints;
    let zero = _mm512_setzero_pd();
    let one = _mm512_set1_pd(1.0);
    let scaled_compliance = _mm512_set1_pd(family.scaled_compliance);
    let gamma = _mm512_set1_pd(family.gamma);
    let delta: [__m512d; 3] = std::array::from_fn(|c| _mm512_sub_pd(a[c], b[c]));
    let length = _mm512_sqrt_pd(dot(delta, delta));
    let inverse_length = _mm512_div_pd(one, length);
    let gradient = delta.map(|d| _mm512_mul_pd(d, inverse_length));
    let constraint = _mm512_sub_pd(length, rest);
    // SAFETY (the multiplier loads and stores): by the caller's contract.
    let correction = if PBD {
        _mm512_mul_pd(negate(constraint), inverse_denominator)
    } else {
        // As in `project`: without multipliers λ and its term are 0.
        let elastic = if MULTIPLIERS {
            let lambda = unsafe { load::<PARTIAL>(lambda_at, count, 0) };
            _mm512_sub_pd(negate(constraint), _mm512_mul_pd(scaled_compliance, lambda))
        } else {
            negate(constraint)
        };
        if DAMPED {
            let moved: [__m512d; 3] = std::array::from_fn(|c| {
                _mm512_sub_pd(
                    _mm512_sub_pd(a[c], previous_a[c]),
                    _mm512_sub_pd(b[c], previous_b[c]),
                )
            });
            let rate = dot(gradient, moved);
            _mm512_mul_pd(
                _mm512_sub_pd(elastic, _mm512_mul_pd(gamma, rate)),
                inverse_denominator,
            )
        } else {
            _mm512_mul_pd(elastic, inverse_denominator)
        }
    };
    // `project`'s `active`: `!=` is true for NaN, as the unordered comparison.
    let active = _mm512_cmp_pd_mask::<_CMP_NEQ_UQ>(inverse_denominator, zero)
        & _mm512_cmp_pd_mask::<_CMP_NEQ_UQ>(length, zero);
    let correction = _mm512_maskz_mov_pd(active, correction);
    let step = gradient.map(|g| _mm512_maskz_mov_pd(active, _mm512_mul_pd(correction, g)));
    if MULTIPLIERS {
        unsafe {
            let lambda = _mm512_add_pd(load::<PARTIAL>(lambda_at, count, 0), correction);
            store::<PARTIAL>(lambda_at, count, 0, lambda);
        }
    }
    [
        std::array::from_fn(|c| _mm512_add_pd(a[c], _mm512_mul_pd(w_a, step[c]))),
        std::array::from_fn(|c| _mm512_sub_pd(b[c], _mm512_mul_pd(w_b, step[c]))),
    ]
}

/// x, y and z of the first `particles` (at most 8) of the 8 consecutive particles at `p`; lanes past
/// them are zero.
///
/// # Safety
/// `3 · particles` `f64` readable at `p`.
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn load_run<const PARTIAL: bool>(p: *const f64, particles: usize) -> [__m512d; 3] {
    // SAFETY: `load` reads only the first `3 · particles` `f64`.
    let r: [__m512d; 3] = std::array::from_fn(|k| unsafe { load::<PARTIAL>(p, 3 * particles, k) });
    std::array::from_fn(|c| {
        let (first, second) = (index(&SPLIT[c].0), index(&SPLIT[c].1));
        _mm512_permutex2var_pd(_mm512_permutex2var_pd(r[0], first, r[1]), second, r[2])
    })
}

/// Writes what [`load_run`] read back to the first `particles` particles at `p`.
///
/// # Safety
/// `3 · particles` `f64` writable at `p`.
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn store_run<const PARTIAL: bool>(p: *mut f64, particles: usize, [x, y, z]: [__m512d; 3]) {
    for (v, merge) in MERGE.iter().enumerate() {
        let xy = _mm512_permutex2var_pd(x, index(&merge.0), y);
        let xyz = _mm512_permutex2var_pd(xy, index(&merge.1), z);
        // SAFETY: `store` writes only the first `3 · particles` `f64`.
        unsafe { store::<PARTIAL>(p, 3 * particles, v, xyz) };
    }
}

/// Projects an apart strip of fewer than eight constraints (constraint `k` joins `x_a[k]` and `x_b[k]`;
/// the slices are those of `grid_constraints::project_apart`) as one masked block, which touches nothing
/// past the strip: the tail of a strip whose whole blocks the vectorised loop takes. That loop's scalar
/// remainder cost a fifth of the apart strips' time on the default flag, whose shear strips have 63
/// constraints (`perf annotate` of `fingerprint time 64x46 1 1500`).
///
/// # Safety
/// The CPU must have AVX-512F.
#[target_feature(enable = "avx512f")]
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn project_apart_partial<
    const PBD: bool,
    const MULTIPLIERS: bool,
    const DAMPED: bool,
>(
    x_a: &mut [DVec3],
    x_b: &mut [DVec3],
    previous_a: &[DVec3],
    previous_b: &[DVec3],
    inverse_mass_a: &[f64],
    inverse_mass_b: &[f64],
    rest_lengths: &[f64],
    inverse_denominators: &[f64],
    lambdas: &mut [f64],
    family: FamilyConstants,
) {
    let n = x_a.len();
    assert!(
        x_b.len() == n
            && previous_a.len() == n
            && previous_b.len() == n
            && inverse_mass_a.len() == n
            && inverse_mass_b.len() == n
    );
    assert!(rest_lengths.len() == n && inverse_denominators.len() == n && lambdas.len() == n);
    assert!(n < BLOCK, "{n} constraints are more than one block");
    if n == 0 {
        return;
    }
    // SAFETY (the loads and stores): the asserts above make `n` particles and constraints valid in
    // every slice; `DVec3` is three `f64` (`repr(C)`).
    unsafe {
        let a_at = x_a.as_mut_ptr().cast::<f64>();
        let b_at = x_b.as_mut_ptr().cast::<f64>();
        let a = load_run::<true>(a_at, n);
        let b = load_run::<true>(b_at, n);
        let previous = if DAMPED {
            [
                load_run::<true>(previous_a.as_ptr().cast(), n),
                load_run::<true>(previous_b.as_ptr().cast(), n),
            ]
        } else {
            [[_mm512_setzero_pd(); 3]; 2]
        };
        let w = [
            load::<true>(inverse_mass_a.as_ptr(), n, 0),
            load::<true>(inverse_mass_b.as_ptr(), n, 0),
        ];
        let constraints = Constraints {
            rest: load::<true>(rest_lengths.as_ptr(), n, 0),
            inverse_denominator: load::<true>(inverse_denominators.as_ptr(), n, 0),
            lambdas: lambdas.as_mut_ptr(),
            count: n,
        };
        let [a, b] =
            solve::<PBD, MULTIPLIERS, DAMPED, true>([a, b], previous, w, constraints, family);
        store_run::<true>(a_at, n, a);
        store_run::<true>(b_at, n, b);
    }
}
