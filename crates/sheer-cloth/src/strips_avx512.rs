//! A grid's strips with AVX-512, eight constraints per vector, without gathers and without scalar
//! remainders.
//!
//! An along strip pairs particles within one row: stretch joins `2m` and `2m + 1`, bending `4m + j` and
//! `4m + j + 2`. Left to the vectoriser, the loop over such pairs read and wrote each component of each
//! end with a gather and a scatter (`objdump` of the two AVX-512 loops: 84 gathers, 60 scatters), and the
//! along strips took 31 % of the default flag's frame for a third of its constraints (`perf record -e
//! cpu-clock` of `fingerprint time 64x46 1 800`). Here, with the state split by component
//! (`components.rs`), a block of 16 particles (eight constraints) is two plain vector loads per
//! component, and the ends of the eight constraints are picked out of them by one two-source permute
//! each; the results go back the same way. (With the particles as 24-byte `DVec3`, the block had first to
//! be split into components by four more permutes per component, and joined again after.) A strip's
//! last, partial block uses masked loads and stores, which touch nothing past the strip.
//!
//! An apart strip needs no permutes (constraint `k` joins particle `k` of two runs), and its whole blocks
//! vectorise well on their own; here it goes block by block with its last few constraints (seven of the
//! 63 of every shear strip of the default flag) as one masked block, in one call ([`project_apart`]).
//!
//! The arithmetic ([`solve`]) is that of [`project`](crate::grid_constraints::project), operation for
//! operation and without fused multiply–adds, so the results are the same bits (tested against it and
//! against the loops in `strip_loops_match_the_one_constraint_projection_bit_for_bit`,
//! `along_strips_of_every_length_match_the_loop_and_touch_nothing_beyond` and
//! `apart_strips_of_every_length_match_the_projection_and_touch_nothing_beyond`; the simulator's
//! fingerprint is unchanged).

use std::arch::x86_64::*;

use crate::components::{XyzMut, XyzRef};
use crate::grid_constraints::FamilyConstants;

/// Constraints per block: one vector of eight `f64`.
pub(crate) const BLOCK: usize = 8;

/// Index vectors of `_mm512_permutex2var_pd`, which picks lane `i` of its result from lane `idx[i]` of
/// the sixteen lanes of its two sources (the first's 0–7, the second's 8–15).
type Index = [i64; 8];

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

/// One component of the first `particles` (at most 16) of the 16 particles at `p`, as the eight first
/// ends then the eight second ends of the block's constraints (picked by `split`, the layout's
/// [`Tables::split_ends`]); lanes past them are zero.
///
/// # Safety
/// `particles` `f64` readable at `p`.
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn load_ends<const PARTIAL: bool>(
    p: *const f64,
    particles: usize,
    split: (__m512i, __m512i),
) -> [__m512d; 2] {
    // SAFETY: `load` reads only the first `particles` `f64`.
    let (low, high) = unsafe {
        (
            load::<PARTIAL>(p, particles, 0),
            load::<PARTIAL>(p, particles, 1),
        )
    };
    [
        _mm512_permutex2var_pd(low, split.0, high),
        _mm512_permutex2var_pd(low, split.1, high),
    ]
}

/// Writes what [`load_ends`] read back to the first `particles` `f64` at `p` (`merge`: the layout's
/// [`Tables::merge_ends`]).
///
/// # Safety
/// `particles` `f64` writable at `p`.
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn store_ends<const PARTIAL: bool>(
    p: *mut f64,
    particles: usize,
    [a, b]: [__m512d; 2],
    merge: [__m512i; 2],
) {
    // SAFETY: `store` writes only the first `particles` `f64`.
    unsafe {
        store::<PARTIAL>(p, particles, 0, _mm512_permutex2var_pd(a, merge[0], b));
        store::<PARTIAL>(p, particles, 1, _mm512_permutex2var_pd(a, merge[1], b));
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
/// missing lanes are loaded as zeros, which make an inactive constraint, and not stored). The arguments
/// are those `project_along` takes: `x`, `previous` (split by component) and `inverse_masses` per
/// particle, the rest per constraint.
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
    mut x: XyzMut<'_>,
    previous: XyzRef<'_>,
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
        constraints.is_multiple_of(HALF),
        "whole chunks of {HALF} constraints"
    );
    let n = 2 * constraints;
    assert!(x.x.len() == n && x.y.len() == n && x.z.len() == n);
    assert!(previous.x.len() == n && previous.y.len() == n && previous.z.len() == n);
    assert!(inverse_masses.len() == n);
    assert!(inverse_denominators.len() == constraints && lambdas.len() == constraints);
    let whole = constraints / BLOCK * BLOCK;
    for first in (0..whole).step_by(BLOCK) {
        // SAFETY: the asserts above make the block's particles and constraints valid.
        unsafe {
            block::<PBD, MULTIPLIERS, DAMPED, HALF, false>(
                &mut x,
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
                &mut x,
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
/// [`project_along`]'s strip.
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
    x: &mut XyzMut<'_>,
    previous: XyzRef<'_>,
    inverse_masses: &[f64],
    rest_lengths: &[f64],
    inverse_denominators: &[f64],
    lambdas: &mut [f64],
    family: FamilyConstants,
    first: usize,
    count: usize,
) {
    let tables = &TABLES[HALF - 1];
    let split = (index(&tables.split_ends.0), index(&tables.split_ends.1));
    let merge = [index(&tables.merge_ends[0]), index(&tables.merge_ends[1])];
    let particles = 2 * count;
    let at = 2 * first;
    // SAFETY (the loads and stores below): by the caller's contract, `particles` particles and `count`
    // constraints from the block's first are valid.
    unsafe {
        let [ax, bx] = load_ends::<PARTIAL>(x.x.as_ptr().add(at), particles, split);
        let [ay, by] = load_ends::<PARTIAL>(x.y.as_ptr().add(at), particles, split);
        let [az, bz] = load_ends::<PARTIAL>(x.z.as_ptr().add(at), particles, split);
        let [w_a, w_b] = load_ends::<PARTIAL>(inverse_masses.as_ptr().add(at), particles, split);
        let previous_ends = if DAMPED {
            let [pax, pbx] = load_ends::<PARTIAL>(previous.x.as_ptr().add(at), particles, split);
            let [pay, pby] = load_ends::<PARTIAL>(previous.y.as_ptr().add(at), particles, split);
            let [paz, pbz] = load_ends::<PARTIAL>(previous.z.as_ptr().add(at), particles, split);
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
        store_ends::<PARTIAL>(x.x.as_mut_ptr().add(at), particles, [ax, bx], merge);
        store_ends::<PARTIAL>(x.y.as_mut_ptr().add(at), particles, [ay, by], merge);
        store_ends::<PARTIAL>(x.z.as_mut_ptr().add(at), particles, [az, bz], merge);
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

/// x, y and z of vector block `k` (vectors `8k..8k + 8`) of the first `n` vectors of `v`; with `PARTIAL`,
/// lanes past them are zero and not read.
///
/// # Safety
/// `n` vectors in `v`, and block `k` whole unless `PARTIAL`.
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn load_xyz<const PARTIAL: bool>(v: XyzRef<'_>, n: usize, k: usize) -> [__m512d; 3] {
    // SAFETY: `load` reads only the first `n` `f64` of each component.
    unsafe {
        [
            load::<PARTIAL>(v.x.as_ptr(), n, k),
            load::<PARTIAL>(v.y.as_ptr(), n, k),
            load::<PARTIAL>(v.z.as_ptr(), n, k),
        ]
    }
}

/// Projects an apart strip (constraint `k` joins `x_a[k]` and `x_b[k]`; the slices are those of
/// `grid_constraints::project_apart`), eight constraints a block and the last few as one masked block,
/// which touches nothing past the strip.
///
/// Whole blocks had gone through the vectorised loop (`grid_constraints::project_apart`) and the tail
/// through a masked block of its own: two calls per strip, each passing eighteen slices through the
/// run-time dispatch of `by_cpu!`, which with the strip's own dispatch took about 8 % of the default
/// flag's frame for strips of 63 or 64 constraints (`perf record -e cpu-clock` of `fingerprint time 64x46
/// 1 3000`). (Before the tail was masked, the loop's scalar remainder cost a fifth of the apart strips'
/// time.)
///
/// # Safety
/// The CPU must have AVX-512F.
#[target_feature(enable = "avx512f")]
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn project_apart<const PBD: bool, const MULTIPLIERS: bool, const DAMPED: bool>(
    x_a: XyzMut<'_>,
    x_b: XyzMut<'_>,
    previous_a: XyzRef<'_>,
    previous_b: XyzRef<'_>,
    inverse_mass_a: &[f64],
    inverse_mass_b: &[f64],
    rest_lengths: &[f64],
    inverse_denominators: &[f64],
    lambdas: &mut [f64],
    family: FamilyConstants,
) {
    let n = x_a.x.len();
    assert!(x_a.y.len() == n && x_a.z.len() == n && x_b.x.len() == n);
    assert!(x_b.y.len() == n && x_b.z.len() == n);
    assert!(previous_a.x.len() == n && previous_a.y.len() == n && previous_a.z.len() == n);
    assert!(previous_b.x.len() == n && previous_b.y.len() == n && previous_b.z.len() == n);
    assert!(inverse_mass_a.len() == n && inverse_mass_b.len() == n);
    assert!(rest_lengths.len() == n && inverse_denominators.len() == n && lambdas.len() == n);
    let mut strip = ApartStrip {
        x_a,
        x_b,
        previous_a,
        previous_b,
        inverse_mass_a,
        inverse_mass_b,
        rest_lengths,
        inverse_denominators,
        lambdas,
        n,
    };
    for k in 0..n / BLOCK {
        // SAFETY: the asserts above make the `n` particles and constraints valid in every slice, and
        // block `k` is whole.
        unsafe { apart_block::<PBD, MULTIPLIERS, DAMPED, false>(&mut strip, k, family) };
    }
    if !n.is_multiple_of(BLOCK) {
        // SAFETY: as above; the masked block reads and writes only the first `n`.
        unsafe { apart_block::<PBD, MULTIPLIERS, DAMPED, true>(&mut strip, n / BLOCK, family) };
    }
}

/// The slices of [`project_apart`], all `n` long.
struct ApartStrip<'a, 'b> {
    x_a: XyzMut<'a>,
    x_b: XyzMut<'a>,
    previous_a: XyzRef<'a>,
    previous_b: XyzRef<'a>,
    inverse_mass_a: &'a [f64],
    inverse_mass_b: &'a [f64],
    rest_lengths: &'a [f64],
    inverse_denominators: &'a [f64],
    lambdas: &'b mut [f64],
    n: usize,
}

/// Projects block `k` of an apart strip (masked past its `n` constraints with `PARTIAL`).
///
/// # Safety
/// The slices of `strip` all `strip.n` long, and block `k` whole unless `PARTIAL`.
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn apart_block<
    const PBD: bool,
    const MULTIPLIERS: bool,
    const DAMPED: bool,
    const PARTIAL: bool,
>(
    strip: &mut ApartStrip<'_, '_>,
    k: usize,
    family: FamilyConstants,
) {
    let n = strip.n;
    // SAFETY (the loads and stores): by the caller's contract.
    unsafe {
        let a = load_xyz::<PARTIAL>(strip.x_a.as_ref(), n, k);
        let b = load_xyz::<PARTIAL>(strip.x_b.as_ref(), n, k);
        let previous = if DAMPED {
            [
                load_xyz::<PARTIAL>(strip.previous_a, n, k),
                load_xyz::<PARTIAL>(strip.previous_b, n, k),
            ]
        } else {
            [[_mm512_setzero_pd(); 3]; 2]
        };
        let w = [
            load::<PARTIAL>(strip.inverse_mass_a.as_ptr(), n, k),
            load::<PARTIAL>(strip.inverse_mass_b.as_ptr(), n, k),
        ];
        let first = BLOCK * k;
        let count = n.saturating_sub(first).min(BLOCK);
        let constraints = Constraints {
            rest: load::<PARTIAL>(strip.rest_lengths.as_ptr(), n, k),
            inverse_denominator: load::<PARTIAL>(strip.inverse_denominators.as_ptr(), n, k),
            lambdas: strip.lambdas.as_mut_ptr().add(first),
            count,
        };
        let [a, b] =
            solve::<PBD, MULTIPLIERS, DAMPED, PARTIAL>([a, b], previous, w, constraints, family);
        for (x, [x_x, x_y, x_z]) in [(&mut strip.x_a, a), (&mut strip.x_b, b)] {
            store::<PARTIAL>(x.x.as_mut_ptr(), n, k, x_x);
            store::<PARTIAL>(x.y.as_mut_ptr(), n, k, x_y);
            store::<PARTIAL>(x.z.as_mut_ptr(), n, k, x_z);
        }
    }
}
