//! Analog Monte Carlo photon transport through the same slab as [`crate::slab`]: exponential free paths
//! in optical depth, absorption with probability `1 − Λ` at each interaction, isotropic re-emission.
//! It shares no code with the deterministic solver, which makes it an independent check.
//!
//! Photons are counted into uniform bins of the emergent cosine μ on each face. Each of the N photons
//! stands for `F_in / N` of the flux `F_in` the light delivers per unit area of the lit face
//! ([`Incidence::flux`]), so the binned flux of a band `[μa, μb]` estimates `2π ∫_{μa}^{μb} L(μ) μ dμ`:
//!
//! * a beam at μ0 ([`simulate_photons`]) of unit irradiance normal to it delivers `F_in = μ0`, and `L` is
//!   the solver's radiance per unit normal irradiance;
//! * uniform unit radiance over the lit face's hemisphere ([`simulate_photons_diffuse`]) delivers
//!   `F_in = ∫ μ0 dΩ = π`; a photon arriving from it has μ0 distributed with density `2μ0` (the
//!   photons crossing unit area from `dΩ` are proportional to `μ0 dΩ`), drawn as `μ0 = √(1 − U)`. The
//!   emergent radiance is then `L = R_d(μ)` (lit face) or `T_d(μ)` (unlit face) of [`crate::diffuse`], so a
//!   band's flux estimates `2π ∫_{μa}^{μb} R_d(μ) μ dμ` (or `T_d`), the direct count
//!   `2π ∫_0^1 e^{−τ1/μ} μ dμ = 2π E3(τ1)`, and the absorbed count `2π ∫_0^1 A(μ) μ dμ`.
//!
//! Counts are binomial, so a bin's standard error is `F_in √(p(1−p)/N)` with `p` the fraction counted.
//!
//! Two slabs ([`simulate_two_slabs`]): a beam at μ0 of unit normal irradiance enters the front slab,
//! and photons move between it and a parallel back slab behind it. The slabs are infinitely wide, so the
//! gap between them does not matter: a photon leaving the front slab's far face enters the back slab's
//! near face in the same direction, one leaving the back slab's near face re-enters the front slab's
//! far face, and photons leaving the front slab towards the light or the back slab's far face escape.
//! Each photon again stands for `μ0 / N`, and the tallies estimate the back slab's own scattered
//! radiance, the light whose last interaction was in the back slab, leaving through
//!
//! * its far face ([`TwoSlabTally::far`]): band flux `2π ∫ L_far(μ) μ dμ`;
//! * its near face, counted as it leaves the back slab, before it re-enters the front one
//!   ([`TwoSlabTally::lit`]): band flux `2π ∫ L_lit(μ) μ dμ`.
//!
//! Light the front slab scatters and that then crosses the back slab without interacting is not the back
//! slab's radiance and is not counted. A photon can leave the back slab's near face more than once (it is
//! scattered back by the front slab and scattered again by the back one), so those counts are not
//! binomial: [`FaceTally`] keeps each photon's squared counts for the standard error. The subsets
//! [`TwoSlabTally::far_direct`] and [`TwoSlabTally::lit_direct`] count the crossings of photons that
//! have not interacted in the front slab: they reached the back slab in the unscattered beam, and
//! estimate exactly `t1 × ` the back slab's own response to that beam, `t1 = e^{−τ1_front/μ0}`.
//!
//! Randomness: xoshiro256++ (Blackman & Vigna 2018) seeded per batch of photons through splitmix64, so
//! results depend only on the seed and photon count, not on the number of rayon threads.

use rayon::prelude::*;

use crate::{Result, TransportError, validate};

/// How photons enter the lit face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Incidence {
    /// A collimated beam at cosine `mu0` ∈ (0, 1] of unit irradiance normal to it.
    Beam {
        /// Incident cosine μ0.
        mu0: f64,
    },
    /// Uniform unit radiance over the lit face's whole hemisphere (cosine-weighted directions).
    Diffuse,
}

impl Incidence {
    /// Flux delivered per unit area of the lit face (W m⁻² per unit normal irradiance for a beam, per
    /// unit radiance in W m⁻² sr⁻¹ for diffuse light): `μ0`, or `π` for diffuse light.
    pub fn flux(&self) -> f64 {
        match *self {
            Incidence::Beam { mu0 } => mu0,
            Incidence::Diffuse => std::f64::consts::PI,
        }
    }

    /// The inward cosine of the next photon (the only thing that differs between incidences).
    fn draw_cosine(&self, rng: &mut Xoshiro256PlusPlus) -> f64 {
        match *self {
            Incidence::Beam { mu0 } => mu0,
            // Density 2μ0 on (0, 1]: inverse of the distribution μ0², with 1 − U ∈ (0, 1] so that no
            // photon runs parallel to the face.
            Incidence::Diffuse => (1.0 - rng.uniform()).sqrt(),
        }
    }
}

/// Photons per independently seeded batch (the unit of parallel work).
const BATCH: u64 = 1 << 16;

/// splitmix64 step (Steele, Lea & Flood 2014): seeds xoshiro from one 64-bit value.
fn splitmix64(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// xoshiro256++ generator.
struct Xoshiro256PlusPlus {
    state: [u64; 4],
}

impl Xoshiro256PlusPlus {
    fn seeded(seed: u64) -> Self {
        let mut s = seed;
        Self {
            state: [
                splitmix64(&mut s),
                splitmix64(&mut s),
                splitmix64(&mut s),
                splitmix64(&mut s),
            ],
        }
    }

    fn next_u64(&mut self) -> u64 {
        let s = &mut self.state;
        let result = (s[0].wrapping_add(s[3])).rotate_left(23).wrapping_add(s[0]);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        result
    }

    /// Uniform in [0, 1) with 53 random bits.
    fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// Photon counts of one simulation.
#[derive(Clone, Debug, PartialEq)]
pub struct MonteCarloTally {
    /// Photons launched.
    pub photons: u64,
    /// How they entered (the flux each stands for: [`Incidence::flux`] / photons).
    pub incidence: Incidence,
    /// Scattered photons leaving the lit face, per uniform μ bin.
    pub reflected: Vec<u64>,
    /// Scattered photons leaving the unlit face, per uniform μ bin.
    pub transmitted: Vec<u64>,
    /// Photons crossing the slab without interacting.
    pub direct: u64,
    /// Photons absorbed.
    pub absorbed: u64,
}

impl MonteCarloTally {
    /// A tally of no photons under `incidence`, `bins` empty bins a face.
    fn empty(incidence: Incidence, bins: usize) -> Self {
        MonteCarloTally {
            photons: 0,
            incidence,
            reflected: vec![0; bins],
            transmitted: vec![0; bins],
            direct: 0,
            absorbed: 0,
        }
    }

    /// The photons of `self` and `other` (the same incidence and bins) in one tally.
    fn merged(mut self, other: Self) -> Self {
        self.photons += other.photons;
        for (sum, add) in self.reflected.iter_mut().zip(&other.reflected) {
            *sum += add;
        }
        for (sum, add) in self.transmitted.iter_mut().zip(&other.transmitted) {
            *sum += add;
        }
        self.direct += other.direct;
        self.absorbed += other.absorbed;
        self
    }

    /// Number of μ bins on each face.
    pub fn bins(&self) -> usize {
        self.reflected.len()
    }

    /// The cosine band `[μa, μb]` of bin `index`.
    pub fn bin_band(&self, index: usize) -> (f64, f64) {
        let n = self.bins() as f64;
        (index as f64 / n, (index + 1) as f64 / n)
    }

    /// Estimated flux and its standard error for `count` of the photons (per unit normal irradiance of
    /// a beam, per unit radiance of diffuse light; see the module docs); a count beyond the photons
    /// launched is an error (its variance would be negative: NaN).
    pub fn flux_with_error(&self, count: u64) -> Result<(f64, f64)> {
        if self.photons == 0 {
            return Err(TransportError::PhotonCount);
        }
        if count > self.photons {
            return Err(TransportError::Count {
                count,
                photons: self.photons,
            });
        }
        let p = count as f64 / self.photons as f64;
        let flux = self.incidence.flux();
        Ok((
            flux * p,
            flux * (p * (1.0 - p) / self.photons as f64).sqrt(),
        ))
    }
}

/// Most μ bins per face: far finer than any photon count resolves. A tally holds two `u64` a bin
/// (32 MiB at this many), and a run keeps a few per thread alive (`usize::MAX` bins panicked).
pub const MAX_BINS: usize = 1 << 20;

/// Launches `photons` photons at `mu0` ∈ (0, 1] into a slab of optical thickness `tau1` and albedo Λ,
/// tallying emergent scattered photons into `bins` uniform μ bins per face. Deterministic in `seed`.
pub fn simulate_photons(
    tau1: f64,
    albedo: f64,
    mu0: f64,
    photons: u64,
    bins: usize,
    seed: u64,
) -> Result<MonteCarloTally> {
    simulate(tau1, albedo, Incidence::Beam { mu0 }, photons, bins, seed)
}

/// Launches `photons` photons from uniform radiance over the lit face's hemisphere (cosine-weighted
/// directions, module docs) into a slab of optical thickness `tau1` and albedo Λ, tallying emergent
/// scattered photons into `bins` uniform μ bins per face. Deterministic in `seed`. Binned fluxes are
/// per unit incident radiance and estimate `2π ∫ R_d(μ) μ dμ` and `2π ∫ T_d(μ) μ dμ` over each band.
pub fn simulate_photons_diffuse(
    tau1: f64,
    albedo: f64,
    photons: u64,
    bins: usize,
    seed: u64,
) -> Result<MonteCarloTally> {
    simulate(tau1, albedo, Incidence::Diffuse, photons, bins, seed)
}

/// The photon loop shared by both incidences; only the initial direction differs.
fn simulate(
    tau1: f64,
    albedo: f64,
    incidence: Incidence,
    photons: u64,
    bins: usize,
    seed: u64,
) -> Result<MonteCarloTally> {
    validate::optical_thickness(tau1)?;
    validate::albedo(albedo)?;
    if let Incidence::Beam { mu0 } = incidence {
        validate::incident_cosine(mu0)?;
    }
    if photons == 0 {
        return Err(TransportError::PhotonCount);
    }
    if !(1..=MAX_BINS).contains(&bins) {
        return Err(TransportError::Bins(bins));
    }
    Ok(run_batches(
        photons,
        seed,
        |count, rng| simulate_batch(tau1, albedo, incidence, count, bins, rng),
        || MonteCarloTally::empty(incidence, bins),
        MonteCarloTally::merged,
    ))
}

/// Runs `photons` photons in batches of [`BATCH`], batch `b` on its own generator seeded from `seed`
/// and `b`, on rayon, and merges the batches' tallies. Tallies are summed as they finish, so that at
/// most a few are alive at once (collecting one per batch held all of them); they hold integer counts,
/// so the totals are the same in any order, on any thread count.
fn run_batches<T: Send>(
    photons: u64,
    seed: u64,
    batch: impl Fn(u64, &mut Xoshiro256PlusPlus) -> T + Sync + Send,
    empty: impl Fn() -> T + Sync + Send,
    merge: impl Fn(T, T) -> T + Sync + Send,
) -> T {
    (0..photons.div_ceil(BATCH))
        .into_par_iter()
        .map(|index| {
            let count = BATCH.min(photons - index * BATCH);
            let mut seed_state = seed ^ index.wrapping_mul(0xd1b5_4a32_d192_ed03);
            let mut rng = Xoshiro256PlusPlus::seeded(splitmix64(&mut seed_state));
            batch(count, &mut rng)
        })
        .reduce(empty, merge)
}

fn simulate_batch(
    tau1: f64,
    albedo: f64,
    incidence: Incidence,
    photons: u64,
    bins: usize,
    rng: &mut Xoshiro256PlusPlus,
) -> MonteCarloTally {
    let mut tally = MonteCarloTally {
        photons,
        ..MonteCarloTally::empty(incidence, bins)
    };
    let bin_of = |mu: f64| ((mu * bins as f64) as usize).min(bins - 1);
    for _ in 0..photons {
        // Depth below the lit face and direction cosine along +depth (into the slab).
        let mut depth = 0.0;
        let mut inward_cosine = incidence.draw_cosine(rng);
        let mut scattered = false;
        loop {
            // 1 − U lies in (0, 1], so the logarithm is finite.
            let path = -(1.0 - rng.uniform()).ln();
            let next = depth + inward_cosine * path;
            if next < 0.0 {
                // Only a scattered photon can travel outwards.
                tally.reflected[bin_of(-inward_cosine)] += 1;
                break;
            }
            if next > tau1 {
                if scattered {
                    tally.transmitted[bin_of(inward_cosine)] += 1;
                } else {
                    tally.direct += 1;
                }
                break;
            }
            depth = next;
            if rng.uniform() >= albedo {
                tally.absorbed += 1;
                break;
            }
            scattered = true;
            inward_cosine = 2.0 * rng.uniform() - 1.0;
        }
    }
    tally
}

/// One slab of a two-slab stack: optical thickness `tau1` > 0 and single-scattering albedo Λ ∈ [0, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlabLayer {
    /// Optical thickness τ1.
    pub tau1: f64,
    /// Single-scattering albedo Λ.
    pub albedo: f64,
}

/// Crossings of one face of the back slab of a two-slab run, per uniform μ bin, with the second moments
/// that their standard errors need (module docs: a photon may cross a face more than once).
#[derive(Clone, Debug, PartialEq)]
pub struct FaceTally {
    /// Photons launched.
    pub photons: u64,
    /// Flux each photon stands for, times the photons: the incident cosine μ0 of the unit beam.
    pub incident_flux: f64,
    /// Crossings per bin.
    pub counts: Vec<u64>,
    /// Per bin, the sum over photons of the square of that photon's crossings in the bin.
    pub squares: Vec<u64>,
    /// The sum over photons of the square of that photon's crossings of the whole face.
    pub total_squares: u64,
}

impl FaceTally {
    fn empty(incident_flux: f64, bins: usize) -> Self {
        FaceTally {
            photons: 0,
            incident_flux,
            counts: vec![0; bins],
            squares: vec![0; bins],
            total_squares: 0,
        }
    }

    fn merge(&mut self, other: &Self) {
        self.photons += other.photons;
        for (sum, add) in self.counts.iter_mut().zip(&other.counts) {
            *sum += add;
        }
        for (sum, add) in self.squares.iter_mut().zip(&other.squares) {
            *sum += add;
        }
        self.total_squares += other.total_squares;
    }

    /// Number of μ bins.
    pub fn bins(&self) -> usize {
        self.counts.len()
    }

    /// The cosine band `[μa, μb]` of bin `index`.
    pub fn bin_band(&self, index: usize) -> (f64, f64) {
        let n = self.bins() as f64;
        (index as f64 / n, (index + 1) as f64 / n)
    }

    /// Estimated flux `2π ∫ L μ dμ` over bin `bin`'s band, per unit normal irradiance of the beam, and
    /// its standard error; `None` for a bin beyond the last.
    pub fn band_flux(&self, bin: usize) -> Option<(f64, f64)> {
        Some(self.estimate(*self.counts.get(bin)?, *self.squares.get(bin)?))
    }

    /// Estimated flux `2π ∫_0^1 L μ dμ` through the whole face, and its standard error.
    pub fn total_flux(&self) -> (f64, f64) {
        self.estimate(self.counts.iter().sum(), self.total_squares)
    }

    /// Mean and standard error of the mean of per-photon counts `n` with `Σn = sum` and
    /// `Σn² = squares`, times the incident flux (for 0/1 counts the binomial `√(p(1−p)/N)`).
    fn estimate(&self, sum: u64, squares: u64) -> (f64, f64) {
        let n = self.photons.max(1) as f64;
        let mean = sum as f64 / n;
        let variance = (squares as f64 / n - mean * mean).max(0.0);
        (
            self.incident_flux * mean,
            self.incident_flux * (variance / n).sqrt(),
        )
    }
}

/// Tallies of a two-slab run (module docs, "Two slabs"): the back slab's scattered light by face.
#[derive(Clone, Debug, PartialEq)]
pub struct TwoSlabTally {
    /// Leaving the back slab's far face, last interaction in the back slab: `L_far`.
    pub far: FaceTally,
    /// Leaving the back slab's near face towards the front slab, last interaction in the back slab:
    /// `L_lit`.
    pub lit: FaceTally,
    /// The part of `far` from photons with no interaction in the front slab: `t1 T_back(μ0, μ)`.
    pub far_direct: FaceTally,
    /// The part of `lit` from photons with no interaction in the front slab: `t1 R_back(μ0, μ)`.
    pub lit_direct: FaceTally,
}

impl TwoSlabTally {
    fn empty(mu0: f64, bins: usize) -> Self {
        let face = FaceTally::empty(mu0, bins);
        TwoSlabTally {
            far: face.clone(),
            lit: face.clone(),
            far_direct: face.clone(),
            lit_direct: face,
        }
    }

    fn faces_mut(&mut self) -> [&mut FaceTally; 4] {
        [
            &mut self.far,
            &mut self.lit,
            &mut self.far_direct,
            &mut self.lit_direct,
        ]
    }

    fn merged(mut self, mut other: Self) -> Self {
        for (sum, add) in self.faces_mut().into_iter().zip(other.faces_mut()) {
            sum.merge(add);
        }
        self
    }
}

/// Launches `photons` photons of a beam at `mu0` ∈ (0, 1] into the `front` slab of a pair of parallel
/// slabs, the `back` one behind it, and tallies the back slab's scattered light into `bins` uniform μ
/// bins per face (module docs, "Two slabs"). Deterministic in `seed`, whatever the thread count.
pub fn simulate_two_slabs(
    front: SlabLayer,
    back: SlabLayer,
    mu0: f64,
    photons: u64,
    bins: usize,
    seed: u64,
) -> Result<TwoSlabTally> {
    for layer in [front, back] {
        validate::optical_thickness(layer.tau1)?;
        validate::albedo(layer.albedo)?;
    }
    validate::incident_cosine(mu0)?;
    if photons == 0 {
        return Err(TransportError::PhotonCount);
    }
    if !(1..=MAX_BINS).contains(&bins) {
        return Err(TransportError::Bins(bins));
    }
    Ok(run_batches(
        photons,
        seed,
        |count, rng| simulate_two_slab_batch([front, back], mu0, count, bins, rng),
        || TwoSlabTally::empty(mu0, bins),
        TwoSlabTally::merged,
    ))
}

/// Indices into [`TwoSlabTally::faces_mut`].
const FAR: usize = 0;
const LIT: usize = 1;
/// Added to `FAR` or `LIT` for the subset without front-slab interactions.
const DIRECT: usize = 2;

fn simulate_two_slab_batch(
    layers: [SlabLayer; 2],
    mu0: f64,
    photons: u64,
    bins: usize,
    rng: &mut Xoshiro256PlusPlus,
) -> TwoSlabTally {
    let mut tally = TwoSlabTally::empty(mu0, bins);
    for face in tally.faces_mut() {
        face.photons = photons;
    }
    let bin_of = |mu: f64| ((mu * bins as f64) as usize).min(bins - 1);
    // This photon's crossings, (face, bin), squared and summed when it is done.
    let mut crossings: Vec<(usize, usize)> = Vec::new();
    for _ in 0..photons {
        // The slab it is in (0 front, 1 back), the depth below that slab's near face, and the cosine of
        // its direction with the normal pointing away from the light.
        let mut slab = 0;
        let mut depth = 0.0;
        let mut cosine = mu0;
        let mut last_in_back = false;
        let mut front_interacted = false;
        loop {
            // 1 − U lies in (0, 1], so the logarithm is finite. A path cut short at a face is drawn
            // afresh in the next slab: free paths have no memory.
            let next = depth - cosine * (1.0 - rng.uniform()).ln();
            if (0.0..=layers[slab].tau1).contains(&next) {
                depth = next;
                if rng.uniform() >= layers[slab].albedo {
                    break;
                }
                last_in_back = slab == 1;
                front_interacted |= slab == 0;
                cosine = 2.0 * rng.uniform() - 1.0;
                continue;
            }
            let towards_light = next < 0.0;
            if slab == 1 && last_in_back {
                let face = if towards_light { LIT } else { FAR };
                crossings.push((face, bin_of(cosine.abs())));
                if !front_interacted {
                    crossings.push((face + DIRECT, bin_of(cosine.abs())));
                }
            }
            match (slab, towards_light) {
                // Out of the stack: towards the light, or beyond the back slab.
                (0, true) | (1, false) => break,
                (0, false) => (slab, depth) = (1, 0.0),
                _ => (slab, depth) = (0, layers[0].tau1),
            }
        }
        let faces = tally.faces_mut();
        crossings.sort_unstable();
        for run in crossings.chunk_by(|a, b| a == b) {
            let (face, bin) = run[0];
            let n = run.len() as u64;
            faces[face].counts[bin] += n;
            faces[face].squares[bin] += n * n;
        }
        for run in crossings.chunk_by(|a, b| a.0 == b.0) {
            faces[run[0].0].total_squares += (run.len() * run.len()) as u64;
        }
        crossings.clear();
    }
    tally
}
