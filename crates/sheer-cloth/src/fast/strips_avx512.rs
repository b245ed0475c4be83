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
//! 63 of every shear strip of the default flag) as one masked block, and a run of strips (a batch, or a
//! batch's rows) goes in one call, through the whole cloth's arrays ([`project_apart_strips`]).
//!
//! The arithmetic ([`solve`]) is that of [`project`](crate::solver::project), operation for
//! operation and without fused multiply–adds, so the results are the same bits (tested against it and
//! against the loops in `strip_loops_match_the_one_constraint_projection_bit_for_bit`,
//! `along_strips_of_every_length_match_the_loop_and_touch_nothing_beyond` and
//! `apart_strips_of_every_length_match_the_projection_and_touch_nothing_beyond`).

use std::arch::x86_64::*;

use crate::solver::FamilyConstants;

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

/// `(x0·x1 + y0·y1) + z0·z1`, in glam's order.
#[target_feature(enable = "avx512f")]
#[inline]
fn dot(a: [__m512d; 3], b: [__m512d; 3]) -> __m512d {
    _mm512_add_pd(
        _mm512_add_pd(_mm512_mul_pd(a[0], b[0]), _mm512_mul_pd(a[1], b[1])),
        _mm512_mul_pd(a[2], b[2]),
    )
}

/// Projects along strips one after another in one call: strip `(a, first, count)` runs from particle
/// `a` with constraints `first..first + count`, `HALF` per chunk of `2·HALF` particles (constraint
/// `m·HALF + j` of a strip joins its particles `2·HALF·m + j` and `2·HALF·m + j + HALF`); the strips of a
/// batch's consecutive rows, for instance. Eight constraints a block; a strip's last block may be
/// partial (its missing lanes are loaded as zeros, which make an inactive constraint, and not stored).
///
/// # Safety
/// As [`project_apart_strips`].
#[target_feature(enable = "avx512f")]
pub(crate) unsafe fn project_along_strips<
    const PBD: bool,
    const MULTIPLIERS: bool,
    const DAMPED: bool,
    const HALF: usize,
>(
    arrays: StripArrays,
    strips: impl Iterator<Item = (usize, usize, usize)>,
    family: FamilyConstants,
) {
    const {
        assert!(
            HALF == 1 || HALF == 2,
            "along strips pair neighbours 1 or 2 apart"
        )
    };
    for (a, first, count) in strips {
        assert!(
            count.is_multiple_of(HALF),
            "whole chunks of {HALF} constraints"
        );
        assert!(a + 2 * count <= arrays.particles && first + count <= arrays.constraints);
        for k in 0..count / BLOCK {
            // SAFETY: block `k` is whole and within the strip (the asserts above), exclusive by the
            // caller's contract.
            unsafe {
                along_block::<PBD, MULTIPLIERS, DAMPED, HALF, false>(
                    &arrays,
                    a + 2 * BLOCK * k,
                    first + BLOCK * k,
                    BLOCK,
                    family,
                )
            };
        }
        let whole = count / BLOCK * BLOCK;
        if whole < count {
            // SAFETY: as above, for the `count − whole` left.
            unsafe {
                along_block::<PBD, MULTIPLIERS, DAMPED, HALF, true>(
                    &arrays,
                    a + 2 * whole,
                    first + whole,
                    count - whole,
                    family,
                )
            };
        }
    }
}

/// Projects the `count` (8 unless `PARTIAL`) constraints from `first` of an along strip, on the `2·count`
/// particles from `at`.
///
/// # Safety
/// Those particles and constraints valid in `arrays` and exclusive to this thread.
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn along_block<
    const PBD: bool,
    const MULTIPLIERS: bool,
    const DAMPED: bool,
    const HALF: usize,
    const PARTIAL: bool,
>(
    arrays: &StripArrays,
    at: usize,
    first: usize,
    count: usize,
    family: FamilyConstants,
) {
    let tables = &TABLES[HALF - 1];
    let split = (index(&tables.split_ends.0), index(&tables.split_ends.1));
    let merge = [index(&tables.merge_ends[0]), index(&tables.merge_ends[1])];
    let particles = 2 * count;
    // SAFETY: the loads and stores below touch only the `particles` particles from `at` and the `count`
    // constraints from `first` (`load` and `store` mask off the rest), which by the caller's contract
    // are valid in `arrays` and exclusive to this thread.
    unsafe {
        let ends = |p: *const f64| load_ends::<PARTIAL>(p.add(at), particles, split);
        let [ax, bx] = ends(arrays.x[0]);
        let [ay, by] = ends(arrays.x[1]);
        let [az, bz] = ends(arrays.x[2]);
        let [w_a, w_b] = ends(arrays.inverse_masses);
        let previous_ends = if DAMPED {
            let [pax, pbx] = ends(arrays.previous[0]);
            let [pay, pby] = ends(arrays.previous[1]);
            let [paz, pbz] = ends(arrays.previous[2]);
            [[pax, pay, paz], [pbx, pby, pbz]]
        } else {
            [[_mm512_setzero_pd(); 3]; 2]
        };
        let constraints = Constraints {
            rest: load::<PARTIAL>(arrays.rest_lengths.add(first), count, 0),
            inverse_denominator: load::<PARTIAL>(arrays.inverse_denominators.add(first), count, 0),
            lambdas: arrays.lambdas.add(first),
            count,
        };
        let [[ax, ay, az], [bx, by, bz]] = solve::<PBD, MULTIPLIERS, DAMPED, PARTIAL>(
            [[ax, ay, az], [bx, by, bz]],
            previous_ends,
            [w_a, w_b],
            constraints,
            family,
        );
        store_ends::<PARTIAL>(arrays.x[0].add(at), particles, [ax, bx], merge);
        store_ends::<PARTIAL>(arrays.x[1].add(at), particles, [ay, by], merge);
        store_ends::<PARTIAL>(arrays.x[2].add(at), particles, [az, bz], merge);
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

/// The arithmetic of [`project`](crate::solver::project) on eight constraints at once: the
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
    let delta: [__m512d; 3] = std::array::from_fn(|c| _mm512_sub_pd(a[c], b[c]));
    let squared_length = dot(delta, delta);
    let inverse_squared_length = _mm512_div_pd(_mm512_set1_pd(1.0), squared_length);
    let length = _mm512_sqrt_pd(squared_length);
    let elastic = _mm512_sub_pd(rest, length);
    let elastic = if !PBD && MULTIPLIERS {
        // SAFETY: with `MULTIPLIERS`, `count` multipliers are readable at `lambda_at` (the caller's
        // contract), and `load` reads only those.
        let lambda = unsafe { load::<PARTIAL>(lambda_at, count, 0) };
        _mm512_sub_pd(
            elastic,
            _mm512_mul_pd(_mm512_set1_pd(family.scaled_compliance), lambda),
        )
    } else {
        elastic
    };
    let numerator = if !PBD && DAMPED {
        let moved: [__m512d; 3] = std::array::from_fn(|c| {
            _mm512_sub_pd(
                _mm512_sub_pd(a[c], previous_a[c]),
                _mm512_sub_pd(b[c], previous_b[c]),
            )
        });
        _mm512_sub_pd(
            _mm512_mul_pd(elastic, length),
            _mm512_mul_pd(_mm512_set1_pd(family.gamma), dot(delta, moved)),
        )
    } else {
        _mm512_mul_pd(elastic, length)
    };
    // `project`'s `active`: `!=` is true for NaN, as the unordered comparison; `>=` false, as the
    // ordered one.
    let active = _mm512_cmp_pd_mask::<_CMP_NEQ_UQ>(inverse_denominator, zero)
        & _mm512_cmp_pd_mask::<_CMP_GE_OQ>(squared_length, _mm512_set1_pd(f64::MIN_POSITIVE));
    let coefficient = _mm512_maskz_mul_pd(
        active,
        numerator,
        _mm512_mul_pd(inverse_denominator, inverse_squared_length),
    );
    if MULTIPLIERS {
        // SAFETY: with `MULTIPLIERS`, `count` multipliers are readable and writable at `lambda_at` (the
        // caller's contract), and `load` and `store` touch only those.
        unsafe {
            let change = _mm512_maskz_mul_pd(active, coefficient, length);
            let lambda = _mm512_add_pd(load::<PARTIAL>(lambda_at, count, 0), change);
            store::<PARTIAL>(lambda_at, count, 0, lambda);
        }
    }
    let step = delta.map(|d| _mm512_maskz_mul_pd(active, coefficient, d));
    [
        std::array::from_fn(|c| _mm512_add_pd(a[c], _mm512_mul_pd(w_a, step[c]))),
        std::array::from_fn(|c| _mm512_sub_pd(b[c], _mm512_mul_pd(w_b, step[c]))),
    ]
}

/// The whole cloth's arrays a strip reads and writes, as base pointers: each strip's ends and
/// constraints are then offsets from them (for an apart strip, two index registers for all of them).
/// With a pointer per end and component, eighteen in all, the loop kept some on the stack and shuffled
/// the rest between registers every block: 35 of its 110 instructions.
#[derive(Clone, Copy)]
pub(crate) struct StripArrays {
    /// Positions by component, and their length.
    pub x: [*mut f64; 3],
    pub particles: usize,
    /// Start positions by component (read only when damped), as long.
    pub previous: [*const f64; 3],
    /// Inverse masses, as long.
    pub inverse_masses: *const f64,
    /// Per constraint, `constraints` long: rest lengths, inverted divisors and multipliers (read and
    /// written only with multipliers).
    pub rest_lengths: *const f64,
    pub inverse_denominators: *const f64,
    pub lambdas: *mut f64,
    pub constraints: usize,
}

impl StripArrays {
    /// The arrays from the first element of each, with the particle and constraint counts they share:
    /// `x` and `previous` by component (each `particles` long), `lambdas` as long as the other
    /// per-constraint arrays or longer.
    pub(crate) fn new(
        (x, particles): ([*mut f64; 3], usize),
        (previous, previous_len): ([*const f64; 3], usize),
        inverse_masses: &[f64],
        rest_lengths: &[f64],
        inverse_denominators: &[f64],
        (lambdas, lambdas_len): (*mut f64, usize),
    ) -> StripArrays {
        assert!(previous_len == particles && inverse_masses.len() == particles);
        StripArrays {
            x,
            particles,
            previous,
            inverse_masses: inverse_masses.as_ptr(),
            rest_lengths: rest_lengths.as_ptr(),
            inverse_denominators: inverse_denominators.as_ptr(),
            lambdas,
            constraints: rest_lengths
                .len()
                .min(inverse_denominators.len())
                .min(lambdas_len),
        }
    }
}

/// Projects apart strips one after another in one call: strip `(a, b, first, count)` joins particles
/// `a + k` and `b + k` by constraint `first + k`, for `k < count`, eight constraints a block, the last
/// few as one masked block that touches nothing past the strip.
///
/// A strip of the default flag is 63 or 64 constraints, eight blocks; one call per strip cost about a
/// fifth of the strips' time (a stand-alone loop over 23 strips of 64 took 1.74–1.89 ns a constraint
/// with a call each, 1.42–1.48 ns in one call): each call's set-up, and a chain of dependent operations
/// that the next strip's blocks could not overlap until the call was over.
///
/// # Safety
/// The CPU must have AVX-512F. The arrays valid for their lengths; `a + count ≤ b`; and no other thread
/// may touch the strips' particles or constraints while this runs (reads of `previous` excepted).
#[target_feature(enable = "avx512f")]
pub(crate) unsafe fn project_apart_strips<
    const PBD: bool,
    const MULTIPLIERS: bool,
    const DAMPED: bool,
>(
    arrays: StripArrays,
    strips: impl Iterator<Item = (usize, usize, usize, usize)>,
    family: FamilyConstants,
) {
    for (a, b, first, count) in strips {
        assert!(a + count <= b && b + count <= arrays.particles);
        assert!(first + count <= arrays.constraints);
        for k in 0..count / BLOCK {
            // SAFETY: block `k` is whole and within the strip (the asserts above), exclusive by the
            // caller's contract.
            unsafe {
                apart_block::<PBD, MULTIPLIERS, DAMPED, false>(
                    &arrays,
                    [a, b, first].map(|i| i + BLOCK * k),
                    BLOCK,
                    family,
                )
            };
        }
        if !count.is_multiple_of(BLOCK) {
            let whole = count / BLOCK * BLOCK;
            // SAFETY: as above; the masked block reads and writes only the strip's last constraints.
            unsafe {
                apart_block::<PBD, MULTIPLIERS, DAMPED, true>(
                    &arrays,
                    [a, b, first].map(|i| i + whole),
                    count - whole,
                    family,
                )
            };
        }
    }
}

/// Projects the `count` (8 unless `PARTIAL`) constraints from `first` joining particles from `a` and
/// from `b`.
///
/// # Safety
/// Those particles and constraints valid in `arrays` and exclusive to this thread.
#[target_feature(enable = "avx512f")]
#[inline]
unsafe fn apart_block<
    const PBD: bool,
    const MULTIPLIERS: bool,
    const DAMPED: bool,
    const PARTIAL: bool,
>(
    arrays: &StripArrays,
    [a, b, first]: [usize; 3],
    count: usize,
    family: FamilyConstants,
) {
    // SAFETY: the loads and stores below touch only the `count` particles from `a` and from `b` and the
    // `count` constraints from `first` (`load` and `store` mask off the rest), which by the caller's
    // contract are valid in `arrays` and exclusive to this thread.
    unsafe {
        let load_at = |p: *const f64, i: usize| load::<PARTIAL>(p.add(i), count, 0);
        let x = arrays.x.map(|p| p.cast_const());
        let ends = [x.map(|p| load_at(p, a)), x.map(|p| load_at(p, b))];
        let previous = if DAMPED {
            [
                arrays.previous.map(|p| load_at(p, a)),
                arrays.previous.map(|p| load_at(p, b)),
            ]
        } else {
            [[_mm512_setzero_pd(); 3]; 2]
        };
        let w = [
            load_at(arrays.inverse_masses, a),
            load_at(arrays.inverse_masses, b),
        ];
        let constraints = Constraints {
            rest: load_at(arrays.rest_lengths, first),
            inverse_denominator: load_at(arrays.inverse_denominators, first),
            lambdas: arrays.lambdas.add(first),
            count,
        };
        let [moved_a, moved_b] =
            solve::<PBD, MULTIPLIERS, DAMPED, PARTIAL>(ends, previous, w, constraints, family);
        for c in 0..3 {
            store::<PARTIAL>(arrays.x[c].add(a), count, 0, moved_a[c]);
            store::<PARTIAL>(arrays.x[c].add(b), count, 0, moved_b[c]);
        }
    }
}
