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
    let batches = photons.div_ceil(BATCH);
    // Summed as they finish, so that at most a few tallies are alive at once (collecting one per batch
    // held `batches` of them). Integer counts: the same totals in any order, on any thread count.
    let total = (0..batches)
        .into_par_iter()
        .map(|batch| {
            let count = BATCH.min(photons - batch * BATCH);
            let mut seed_state = seed ^ batch.wrapping_mul(0xd1b5_4a32_d192_ed03);
            let mut rng = Xoshiro256PlusPlus::seeded(splitmix64(&mut seed_state));
            simulate_batch(tau1, albedo, incidence, count, bins, &mut rng)
        })
        .reduce(
            || MonteCarloTally::empty(incidence, bins),
            MonteCarloTally::merged,
        );
    Ok(total)
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
