//! Procedural image assets of the case study: the flag of the Faroe Islands (the cloth's albedo texture Λ) and a
//! watercolour-like painting of a Faroese coast (the background the flag waves in front of).
//!
//! Frisvad, Christensen & Falster (2005) render the Faroese flag in front of a scanned watercolour of a Faroese
//! landscape. We have no scan, so [`faroe_landscape`] paints one: every wash is a layer of pigment glazed over
//! white paper in the subtractive (Beer–Lambert) way of Curtis et al., "Computer-generated watercolor"
//! (SIGGRAPH 1997): reflectance = paper · exp(−Σ density·absorbance). The watercolour effects of that paper that
//! matter at a glance are imitated directly instead of by fluid simulation: the darkened rim where a wash dries
//! (edge darkening), granulation of pigment in the paper's valleys, back-runs ("blooms"), irregular wash edges,
//! paper left white between washes and at the margins, and a fine paper grain.
//!
//! Everything here is a pure function of its arguments; [`write_assets`] is the only function that touches the
//! file system. Rows are computed in parallel, each pixel from its own coordinates only, so the images are
//! identical whatever the rayon thread count.

use std::path::{Path, PathBuf};

use image::RgbImage;
use rayon::prelude::*;

/// Width × height of the committed flag texture: 50 px per construction unit both ways (22 × 16 units).
pub const FLAG_ASSET_SIZE: (u32, u32) = (1100, 800);
/// Width × height of the committed background painting.
pub const LANDSCAPE_ASSET_SIZE: (u32, u32) = (1024, 1024);
/// Seed of the committed background painting.
pub const LANDSCAPE_ASSET_SEED: u64 = 1;
/// File names written by [`write_assets`].
pub const FLAG_FILE_NAME: &str = "faroe_flag.png";
pub const LANDSCAPE_FILE_NAME: &str = "faroe_landscape.png";

/// Largest image this module allocates (bytes of RGB8 data): 2^30, a 16k × 16k-ish image, far beyond any texture
/// the renderer uploads; it keeps a typo in a size from exhausting memory.
const MAX_IMAGE_BYTES: u64 = 1 << 30;

/// Why an asset could not be made or written.
#[derive(Debug, thiserror::Error)]
pub enum AssetError {
    /// The flag's fly is divided into 22 construction units; fewer pixels cannot show the 1-unit blue border.
    #[error(
        "flag width {width} px is too small: at least 22 px are needed for the 22 construction units of its length"
    )]
    FlagTooNarrow { width: u32 },
    /// A painting needs at least one pixel each way.
    #[error("landscape size {width}×{height} px has a zero side")]
    EmptyImage { width: u32, height: u32 },
    /// The requested image would exceed [`MAX_IMAGE_BYTES`].
    #[error("image of {width}×{height} px needs more than {max_bytes} bytes of RGB data")]
    ImageTooLarge {
        width: u32,
        height: u32,
        max_bytes: u64,
    },
    /// The output folder could not be created.
    #[error("cannot create folder {path}: {source}")]
    CreateDir {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The image crate could not encode or write a PNG.
    #[error("cannot write image {path}: {source}")]
    Write {
        path: PathBuf,
        source: image::ImageError,
    },
}

// ---------------------------------------------------------------------------------------------------------------
// The flag
// ---------------------------------------------------------------------------------------------------------------

/// Construction units along the flag's length (hoist to fly): white, blue, red, blue, white.
pub const FLAG_UNITS_LENGTH: [u32; 5] = [6, 1, 2, 1, 12];
/// Construction units along the flag's height (top to bottom): white, blue, red, blue, white.
pub const FLAG_UNITS_HEIGHT: [u32; 5] = [6, 1, 2, 1, 6];
/// White field, sRGB.
pub const FLAG_WHITE: [u8; 3] = [0xFF, 0xFF, 0xFF];
/// Red of the cross, sRGB `#EF303E`: the usual sRGB rendering of Pantone 032 C.
pub const FLAG_RED: [u8; 3] = [0xEF, 0x30, 0x3E];
/// Blue border of the cross, sRGB `#005EB8`: Pantone's sRGB value for Pantone 300 C.
pub const FLAG_BLUE: [u8; 3] = [0x00, 0x5E, 0xB8];

/// The flag of the Faroe Islands (Merkið), `width` px long and `round(width·8/11)` px high.
///
/// Source: the Faroese flag act (løgtingslóg um flagg Føroya, 1959; colours set in the Pantone system by the
/// Løgting on 29 December 1998): a white field with a red Nordic cross bordered in blue; red Pantone 032, blue
/// Pantone 300; proportions 8:11, constructed 6:1:2:1:12 along the length (units of 1/22 of the width) and
/// 6:1:2:1:6 along the height (units of 1/16 of the height). The construction and Pantone shades are as published
/// by the Nordic Council (norden.org, "Færøsk flag") and Flags of the World (fo.html).
///
/// Each pixel gets the exact area fraction of white, blue and red inside its square (the bands are axis-aligned,
/// so the coverage of a pixel factors into a length fraction and a height fraction), blended in linear light and
/// re-encoded as sRGB. Where band edges fall on pixel boundaries (width a multiple of 22 and height a multiple of
/// 16, e.g. 1100 × 800 with 50 px per unit) every pixel is a pure flag colour, identical to classifying it by its
/// centre; elsewhere edge pixels are anti-aliased by their true area coverage.
pub fn faroe_flag(width: u32) -> Result<RgbImage, AssetError> {
    let total_length: u32 = FLAG_UNITS_LENGTH.iter().sum();
    if width < total_length {
        return Err(AssetError::FlagTooNarrow { width });
    }
    let height = flag_height(width);
    check_size(width, height)?;
    let total_height: u32 = FLAG_UNITS_HEIGHT.iter().sum();
    // Cross (blue border and red) and red bands, in construction units.
    let cross_x = band_interval(&FLAG_UNITS_LENGTH, 1, 3);
    let red_x = band_interval(&FLAG_UNITS_LENGTH, 2, 2);
    let cross_y = band_interval(&FLAG_UNITS_HEIGHT, 1, 3);
    let red_y = band_interval(&FLAG_UNITS_HEIGHT, 2, 2);
    let unit_per_px_x = f64::from(total_length) / f64::from(width);
    let unit_per_px_y = f64::from(total_height) / f64::from(height);
    // Per-column and per-row length fractions covered by the cross and by the red bands.
    let column_cover: Vec<(f64, f64)> = (0..width)
        .map(|x| {
            let span = (
                f64::from(x) * unit_per_px_x,
                f64::from(x + 1) * unit_per_px_x,
            );
            (
                interval_fraction(span, cross_x),
                interval_fraction(span, red_x),
            )
        })
        .collect();
    let white = srgb8_to_linear(FLAG_WHITE);
    let red = srgb8_to_linear(FLAG_RED);
    let blue = srgb8_to_linear(FLAG_BLUE);
    let mut image = RgbImage::new(width, height);
    image
        .as_mut()
        .par_chunks_mut(width as usize * 3)
        .enumerate()
        .for_each(|(y, row)| {
            let y = y as f64;
            let span = (y * unit_per_px_y, (y + 1.0) * unit_per_px_y);
            let (cross_fy, red_fy) = (
                interval_fraction(span, cross_y),
                interval_fraction(span, red_y),
            );
            for (pixel, &(cross_fx, red_fx)) in row.chunks_exact_mut(3).zip(&column_cover) {
                // A point is in the red cross if it lies in the red column OR the red row; the area of the
                // complement is the product of the two complements' fractions. Likewise for the whole cross.
                let red_area = 1.0 - (1.0 - red_fx) * (1.0 - red_fy);
                let cross_area = 1.0 - (1.0 - cross_fx) * (1.0 - cross_fy);
                let blue_area = cross_area - red_area;
                let white_area = 1.0 - cross_area;
                let encoded = if red_area == 1.0 {
                    FLAG_RED
                } else if blue_area == 1.0 {
                    FLAG_BLUE
                } else if white_area == 1.0 {
                    FLAG_WHITE
                } else {
                    let mixed: [f64; 3] = std::array::from_fn(|c| {
                        white_area * white[c] + blue_area * blue[c] + red_area * red[c]
                    });
                    linear_to_srgb8(mixed)
                };
                pixel.copy_from_slice(&encoded);
            }
        });
    Ok(image)
}

/// Flag height for a given width, `round(width·8/11)` (8·width/11 is never a half-integer since 11 is odd).
pub fn flag_height(width: u32) -> u32 {
    ((u64::from(width) * 8 + 5) / 11) as u32
}

/// `[start, end)` in construction units of bands `first..=last` of a band list.
fn band_interval(units: &[u32; 5], first: usize, last: usize) -> (f64, f64) {
    let start: u32 = units[..first].iter().sum();
    let end: u32 = units[..=last].iter().sum();
    (f64::from(start), f64::from(end))
}

/// Fraction of `span` covered by `band` (both half-open intervals, `span` non-empty).
fn interval_fraction(span: (f64, f64), band: (f64, f64)) -> f64 {
    let overlap = span.1.min(band.1) - span.0.max(band.0);
    (overlap / (span.1 - span.0)).clamp(0.0, 1.0)
}

fn check_size(width: u32, height: u32) -> Result<(), AssetError> {
    if width == 0 || height == 0 {
        return Err(AssetError::EmptyImage { width, height });
    }
    if u64::from(width) * u64::from(height) * 3 > MAX_IMAGE_BYTES {
        return Err(AssetError::ImageTooLarge {
            width,
            height,
            max_bytes: MAX_IMAGE_BYTES,
        });
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------------------------
// Colour
// ---------------------------------------------------------------------------------------------------------------

/// sRGB transfer function (IEC 61966-2-1), encoded [0, 1] → linear [0, 1].
fn srgb_to_linear(encoded: f64) -> f64 {
    if encoded <= 0.04045 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

/// Inverse sRGB transfer function, linear [0, 1] → encoded [0, 1].
fn linear_to_srgb(linear: f64) -> f64 {
    if linear <= 0.003_130_8 {
        linear * 12.92
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

fn srgb8_to_linear(rgb: [u8; 3]) -> [f64; 3] {
    rgb.map(|c| srgb_to_linear(f64::from(c) / 255.0))
}

fn linear_to_srgb8(rgb: [f64; 3]) -> [u8; 3] {
    // The clamp only absorbs rounding below 0 or above 1 of values that are reflectances by construction.
    rgb.map(|c| (linear_to_srgb(c.clamp(0.0, 1.0)) * 255.0).round() as u8)
}

/// Absorbance −ln T per channel of a pigment that, glazed at density 1 over white paper, shows sRGB colour `rgb`.
fn pigment(rgb: [u8; 3]) -> [f64; 3] {
    // Floor at 1e-4 so that a zero channel is a strong but finite absorber (no infinities, no NaN at density 0).
    srgb8_to_linear(rgb).map(|t| -t.max(1e-4).ln())
}

// ---------------------------------------------------------------------------------------------------------------
// Deterministic value noise
// ---------------------------------------------------------------------------------------------------------------

/// SplitMix64's output mix (Steele, Lea & Flood 2014): a cheap bijective scrambler of 64-bit integers.
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Uniform number in [0, 1) from 53 bits of a hash.
fn unit_from_bits(bits: u64) -> f64 {
    (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Smoothly interpolated lattice ("value") noise in [0, 1] and its fractal sum.
#[derive(Clone, Copy, Debug)]
struct ValueNoise {
    seed: u64,
}

impl ValueNoise {
    fn new(seed: u64, stream: u64) -> Self {
        ValueNoise {
            seed: mix64(seed ^ mix64(stream.wrapping_add(0x9E37_79B9_7F4A_7C15))),
        }
    }

    fn lattice(&self, ix: i64, iy: i64, octave: u64) -> f64 {
        let key = (ix as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (iy as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
            ^ octave.wrapping_mul(0x1656_67B1_9E37_79F9);
        unit_from_bits(mix64(self.seed ^ mix64(key)))
    }

    /// One octave: bilinear interpolation of lattice values with the quintic fade 6t⁵ − 15t⁴ + 10t³ (Perlin 2002),
    /// so the noise has a continuous first and second derivative.
    fn sample(&self, x: f64, y: f64, octave: u64) -> f64 {
        let (fx, fy) = (x.floor(), y.floor());
        let (ix, iy) = (fx as i64, fy as i64);
        let fade = |t: f64| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
        let (tx, ty) = (fade(x - fx), fade(y - fy));
        let top = lerp(
            self.lattice(ix, iy, octave),
            self.lattice(ix + 1, iy, octave),
            tx,
        );
        let bottom = lerp(
            self.lattice(ix, iy + 1, octave),
            self.lattice(ix + 1, iy + 1, octave),
            tx,
        );
        lerp(top, bottom, ty)
    }

    /// Fractal Brownian motion: `octaves` octaves of doubling frequency and halving amplitude, normalised to
    /// [0, 1] (mean 0.5; the sum of independent octaves concentrates around it, standard deviation ≈ 0.15–0.2).
    fn fbm(&self, x: f64, y: f64, octaves: u32) -> f64 {
        let (mut sum, mut norm, mut amplitude, mut frequency) = (0.0, 0.0, 1.0, 1.0);
        for octave in 0..octaves {
            sum += amplitude * self.sample(x * frequency, y * frequency, u64::from(octave));
            norm += amplitude;
            amplitude *= 0.5;
            frequency *= 2.0;
        }
        sum / norm
    }
}

fn lerp(a: f64, b: f64, t: f64) -> f64 {
    a + (b - a) * t
}

fn smoothstep(edge0: f64, edge1: f64, x: f64) -> f64 {
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

// ---------------------------------------------------------------------------------------------------------------
// The painting
// ---------------------------------------------------------------------------------------------------------------

/// Pigments, as the sRGB colour each shows glazed at density 1 over white paper.
mod palette {
    pub const PAPER: [u8; 3] = [0xF8, 0xF4, 0xEA];
    pub const SKY_ULTRAMARINE: [u8; 3] = [0x6A, 0x8C, 0xC0];
    pub const SKY_CERULEAN: [u8; 3] = [0x9C, 0xC2, 0xDC];
    pub const PAYNES_GREY: [u8; 3] = [0x6A, 0x74, 0x84];
    pub const YELLOW_OCHRE: [u8; 3] = [0xE0, 0xC0, 0x78];
    pub const SAP_GREEN: [u8; 3] = [0x6A, 0x9A, 0x38];
    pub const YELLOW_GREEN: [u8; 3] = [0x9C, 0xBA, 0x4A];
    pub const HOOKERS_GREEN: [u8; 3] = [0x3A, 0x66, 0x44];
    pub const SEPIA: [u8; 3] = [0x6E, 0x5C, 0x4C];
    pub const SEA_PRUSSIAN: [u8; 3] = [0x34, 0x5E, 0x88];
    pub const SEA_GREEN: [u8; 3] = [0x4E, 0x82, 0x8A];
}

/// Sea level (the horizon) as a fraction of the image height from the top.
const HORIZON: f64 = 0.52;

/// A back-run: a patch where late water pushed pigment outwards, paler inside and dark at its rim.
#[derive(Clone, Copy, Debug)]
struct Bloom {
    centre: (f64, f64),
    radius: f64,
}

/// A bank of cloud: an ellipse (half sizes in image heights) with a noisy outline.
#[derive(Clone, Copy, Debug)]
struct CloudBank {
    centre: (f64, f64),
    half_size: (f64, f64),
}

/// Signed distance (positive inside, in image heights) of the land masses, for one pixel.
#[derive(Clone, Copy, Debug)]
struct LandDistances {
    near: f64,
    middle: f64,
    stacks: f64,
    far: f64,
}

impl LandDistances {
    fn max(&self) -> f64 {
        self.near.max(self.middle).max(self.stacks).max(self.far)
    }
}

/// Pigments converted to absorbance once.
struct Pigments {
    sky_ultramarine: [f64; 3],
    sky_cerulean: [f64; 3],
    paynes_grey: [f64; 3],
    yellow_ochre: [f64; 3],
    sap_green: [f64; 3],
    yellow_green: [f64; 3],
    hookers_green: [f64; 3],
    sepia: [f64; 3],
    sea_prussian: [f64; 3],
    sea_green: [f64; 3],
}

/// The painting as a function of image position.
struct Painting {
    aspect: f64,
    pixel: f64,
    paper: [f64; 3],
    pigments: Pigments,
    blooms: Vec<Bloom>,
    clouds: Vec<CloudBank>,
    // Independent noise streams, one per purpose, so changing one effect does not reshuffle the others.
    grain: ValueNoise,
    edge: ValueNoise,
    brush: ValueNoise,
    hue: ValueNoise,
    cloud: ValueNoise,
    cloud_shade: ValueNoise,
    sea_streak: ValueNoise,
    sea_crest: ValueNoise,
    profile: ValueNoise,
    strata: ValueNoise,
    bloom_shape: ValueNoise,
}

/// Accumulated absorbance of the washes over one pixel.
#[derive(Clone, Copy, Debug, Default)]
struct Washes {
    absorbance: [f64; 3],
}

impl Washes {
    fn glaze(&mut self, pigment: &[f64; 3], density: f64) {
        for (a, p) in self.absorbance.iter_mut().zip(pigment) {
            *a += density * p;
        }
    }

    /// Two pigments mixed on the palette in proportion `weight` of `second`, laid at `density`.
    fn glaze_mix(&mut self, first: &[f64; 3], second: &[f64; 3], weight: f64, density: f64) {
        let mixed: [f64; 3] = std::array::from_fn(|c| lerp(first[c], second[c], weight));
        self.glaze(&mixed, density);
    }
}

impl Painting {
    fn new(width: u32, height: u32, seed: u64) -> Self {
        let stream = |n: u64| ValueNoise::new(seed, n);
        let blooms = Self::scatter_blooms(seed);
        Painting {
            aspect: f64::from(width) / f64::from(height),
            pixel: 1.0 / f64::from(height),
            paper: srgb8_to_linear(palette::PAPER),
            pigments: Pigments {
                sky_ultramarine: pigment(palette::SKY_ULTRAMARINE),
                sky_cerulean: pigment(palette::SKY_CERULEAN),
                paynes_grey: pigment(palette::PAYNES_GREY),
                yellow_ochre: pigment(palette::YELLOW_OCHRE),
                sap_green: pigment(palette::SAP_GREEN),
                yellow_green: pigment(palette::YELLOW_GREEN),
                hookers_green: pigment(palette::HOOKERS_GREEN),
                sepia: pigment(palette::SEPIA),
                sea_prussian: pigment(palette::SEA_PRUSSIAN),
                sea_green: pigment(palette::SEA_GREEN),
            },
            blooms,
            clouds: Self::scatter_clouds(seed),
            grain: stream(1),
            edge: stream(2),
            brush: stream(3),
            hue: stream(4),
            cloud: stream(5),
            cloud_shade: stream(6),
            sea_streak: stream(7),
            sea_crest: stream(8),
            profile: stream(9),
            strata: stream(10),
            bloom_shape: stream(11),
        }
    }

    /// Four to six banks of cloud in the upper sky (image-width × image-height units).
    fn scatter_clouds(seed: u64) -> Vec<CloudBank> {
        let mut state = mix64(seed ^ 0xC10D_C10D_C10D_C10D);
        let mut next = || {
            state = mix64(state.wrapping_add(0x9E37_79B9_7F4A_7C15));
            unit_from_bits(state)
        };
        let count = 4 + (next() * 3.0) as usize;
        (0..count)
            .map(|index| {
                // Spread across the width: one bank per slot, jittered within it.
                let u = (index as f64 + 0.2 + 0.6 * next()) / count as f64;
                let v = 0.08 + 0.28 * next();
                CloudBank {
                    centre: (u, v),
                    half_size: (0.12 + 0.12 * next(), 0.035 + 0.035 * next()),
                }
            })
            .collect()
    }

    /// A handful of blooms at seeded places in the sky and on the land (in image-width × image-height units).
    fn scatter_blooms(seed: u64) -> Vec<Bloom> {
        let mut state = mix64(seed ^ 0xB100_B100_B100_B100);
        let mut next = || {
            state = mix64(state.wrapping_add(0x9E37_79B9_7F4A_7C15));
            unit_from_bits(state)
        };
        (0..6)
            .map(|_| {
                let u = 0.06 + 0.88 * next();
                let v = 0.06 + 0.58 * next();
                Bloom {
                    centre: (u, v),
                    radius: 0.025 + 0.045 * next(),
                }
            })
            .collect()
    }

    /// Horizontal distance `du` (image widths) in image heights, the unit all distances use.
    fn horizontal(&self, du: f64) -> f64 {
        du * self.aspect
    }

    /// Noise jitter of wash edges, ± `amplitude` image heights, so no silhouette is a clean vector curve.
    fn edge_jitter(&self, u: f64, v: f64, amplitude: f64) -> f64 {
        let x = self.horizontal(u);
        amplitude * 2.0 * (self.edge.fbm(x * 60.0, v * 60.0, 3) - 0.5)
    }

    /// Coverage and edge-darkening factor of a wash whose signed distance (image heights, positive inside) is
    /// `distance`. The rim, where pigment is carried outwards as the wash dries, holds up to `1 + rim` times the
    /// pigment, decaying inwards over `rim_width`.
    fn wash_profile(&self, distance: f64, rim: f64, rim_width: f64) -> f64 {
        let coverage = smoothstep(-0.7 * self.pixel, 0.7 * self.pixel, distance);
        coverage * (1.0 + rim * (-distance.max(0.0) / rim_width).exp())
    }

    /// Top of the near headland (left), image heights from the top, at horizontal position `u`.
    fn near_top(&self, u: f64) -> f64 {
        // A grassy crest, then a convex shoulder falling to the cliff edge, with low undulations.
        0.27 - 0.11 * (-((u - 0.2) / 0.14).powi(2)).exp()
            + 0.05 * (u / 0.42).clamp(0.0, 1.2).powi(3)
            + 0.025 * (self.profile.fbm(u * 7.0, 0.5, 4) - 0.5)
    }

    /// Horizontal position of the near headland's sea cliff at height `v`.
    fn near_face(&self, v: f64) -> f64 {
        // Leaning slightly outwards towards the sea, with ledges from the basalt layers.
        0.41 + 0.07 * ((v - 0.28) / 0.40).clamp(0.0, 1.0).powf(1.5)
            + 0.025 * (self.profile.fbm(3.7, v * 22.0, 4) - 0.5)
    }

    /// Waterline under the near headland: the shore comes towards the viewer on the left.
    fn near_base(&self, u: f64) -> f64 {
        0.64 + 0.08 * (1.0 - u / 0.48).clamp(0.0, 1.0)
            + 0.006 * (self.profile.fbm(u * 30.0, 7.1, 3) - 0.5)
    }

    fn near_distance(&self, u: f64, v: f64) -> f64 {
        let top = v - self.near_top(u);
        let face = self.horizontal(self.near_face(v) - u);
        let base = self.near_base(u) - v;
        top.min(face).min(base)
    }

    /// Top of the middle headland (right), with its summit near u = 0.8.
    fn middle_top(&self, u: f64) -> f64 {
        0.35 - 0.06 * (-((u - 0.80) / 0.13).powi(2)).exp()
            + 0.02 * (self.profile.fbm(u * 9.0, 2.3, 4) - 0.5)
    }

    /// Left sea cliff of the middle headland.
    fn middle_face(&self, v: f64) -> f64 {
        0.615 - 0.03 * ((v - 0.34) / 0.23).clamp(0.0, 1.0)
            + 0.018 * (self.profile.fbm(5.9, v * 25.0, 4) - 0.5)
    }

    const MIDDLE_BASE: f64 = 0.575;

    fn middle_distance(&self, u: f64, v: f64) -> f64 {
        let top = v - self.middle_top(u);
        let face = self.horizontal(u - self.middle_face(v));
        let base = Self::MIDDLE_BASE - v;
        top.min(face).min(base)
    }

    /// Sea stacks (after Risin and Kellingin off Eysturoy): centre u, half width (image heights), top v.
    const STACKS: [(f64, f64, f64); 2] = [(0.525, 0.016, 0.395), (0.565, 0.010, 0.43)];
    const STACK_BASE: f64 = 0.585;

    fn stack_distance(&self, u: f64, v: f64) -> f64 {
        Self::STACKS
            .iter()
            .map(|&(centre, half_width, top)| {
                // Wider at the foot, rough sides.
                let depth = ((v - top) / (Self::STACK_BASE - top)).clamp(0.0, 1.0);
                let half = half_width
                    * (0.7 + 0.5 * depth)
                    * (0.85 + 0.3 * self.profile.fbm(centre * 50.0, v * 40.0, 3));
                let across = self.horizontal((u - centre).abs());
                // Rounded crown: the top drops off towards the sides.
                let crown = v - top - 0.6 * half * (across / half).powi(2);
                (half - across).min(crown).min(Self::STACK_BASE - v)
            })
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Top of the sea stack nearest to horizontal position `u`.
    fn stack_top(&self, u: f64) -> f64 {
        let nearest = Self::STACKS
            .iter()
            .min_by(|a, b| (u - a.0).abs().total_cmp(&(u - b.0).abs()));
        nearest.map_or(0.0, |&(_, _, top)| top)
    }

    /// A pale flat-topped island on the horizon.
    fn far_distance(&self, u: f64, v: f64) -> f64 {
        let shape = (1.0 - ((u - 0.53) / 0.15).powi(2)).max(0.0).powf(0.5);
        let top =
            HORIZON + 0.006 - 0.056 * shape + 0.006 * (self.profile.fbm(u * 20.0, 4.4, 3) - 0.5);
        (v - top).min(HORIZON + 0.004 - v)
    }

    fn land(&self, u: f64, v: f64) -> LandDistances {
        let jitter = self.edge_jitter(u, v, 0.0025);
        LandDistances {
            near: self.near_distance(u, v) + jitter,
            middle: self.middle_distance(u, v) + jitter,
            stacks: self.stack_distance(u, v) + 0.5 * jitter,
            far: self.far_distance(u, v) + 0.5 * jitter,
        }
    }

    /// Painted area inside the deckled paper margin: signed distance (image heights) to the painting's edge.
    fn margin_distance(&self, u: f64, v: f64) -> f64 {
        let to_border = self.horizontal(u.min(1.0 - u)).min(v.min(1.0 - v));
        let margin = 0.022 + 0.012 * self.edge.fbm(self.horizontal(u) * 9.0 + 40.0, v * 9.0, 3);
        to_border - margin
    }

    /// Fraction (0–1) of the sky wash lifted by clouds at (u, v): the union of seeded cloud banks, each an
    /// ellipse whose outline is torn by noise so that it reads as a soft, lifted wet-in-wet shape.
    fn cloud_cover(&self, u: f64, v: f64) -> f64 {
        let x = self.horizontal(u);
        let tear = self.cloud.fbm(x * 4.0 + 11.0, v * 8.0, 5) - 0.5;
        self.clouds
            .iter()
            .map(|bank| {
                let dx = self.horizontal(u - bank.centre.0) / bank.half_size.0;
                let dy = (v - bank.centre.1) / bank.half_size.1;
                // Flatter bottoms: below the centre the ellipse is squashed.
                let dy = if dy > 0.0 { 1.8 * dy } else { dy };
                let inside = 1.0 - (dx * dx + dy * dy).sqrt() + 1.4 * tear;
                smoothstep(0.0, 0.25, inside)
            })
            .fold(0.0, f64::max)
    }

    /// Multiplier of all washes inside and around the blooms: paler inside, darker at the cauliflower rim.
    fn bloom_factor(&self, u: f64, v: f64) -> f64 {
        let mut factor = 1.0;
        for (index, bloom) in self.blooms.iter().enumerate() {
            let dx = self.horizontal(u - bloom.centre.0);
            let dy = v - bloom.centre.1;
            let r = (dx * dx + dy * dy).sqrt();
            if r > 1.6 * bloom.radius {
                continue;
            }
            // Radius modulated around the circle (noise on the unit circle: seamless) into a cauliflower outline.
            let (dir_x, dir_y) = if r > 0.0 {
                (dx / r, dy / r)
            } else {
                (1.0, 0.0)
            };
            let offset = 17.0 * index as f64;
            let lobes = self.bloom_shape.fbm(dir_x * 2.5 + offset, dir_y * 2.5, 4);
            let outline = bloom.radius * (0.65 + 0.7 * lobes);
            let inside = outline - r;
            let rim_width = 0.004;
            factor *= if inside > 0.0 {
                0.88 + 0.32 * (-inside / rim_width).exp()
            } else {
                1.0 + 0.12 * (inside / (0.5 * rim_width)).exp()
            };
        }
        factor
    }

    /// Linear reflectance of the painting at (u, v) ∈ [0, 1]² (image width, image height from the top).
    fn reflectance(&self, u: f64, v: f64) -> [f64; 3] {
        let p = &self.pigments;
        let x = self.horizontal(u);
        let land = self.land(u, v);
        let land_max = land.max();
        let margin = self.margin_distance(u, v) + self.edge_jitter(u + 3.0, v, 0.002);

        // Paper texture: a fine grain (a few px) and the granulation it causes in the heavier pigments.
        let grain = self.grain.fbm(x * 320.0, v * 320.0, 2);
        let clumps = self.grain.fbm(x * 90.0 + 50.0, v * 90.0, 2);
        let granulation = 1.0 + 0.3 * (grain - 0.5) + 0.45 * (clumps - 0.5);
        let brush = self.brush.fbm(x * 2.2, v * 4.0, 5);
        let mut washes = Washes::default();

        // Thin white gaps left between the sky/sea washes and the land, here and there.
        let gap = 1.5 * self.pixel * smoothstep(0.55, 0.7, self.edge.fbm(x * 14.0, v * 14.0, 2));
        let reserve = -land_max - gap;

        // Dried "tide marks": thin rims along level sets of a slow noise, where puddles of a wash dried last.
        let tide_level = self.brush.fbm(x * 3.0 + 7.0, v * 3.0, 3) - 0.5;
        let tide = 1.0 + 0.25 * (-(tide_level / 0.008).powi(2)).exp();

        // --- Sky: graded wash, ultramarine at the top to pale cerulean and a warm glow at the horizon.
        let sky_edge = (HORIZON + 0.004 - v).min(reserve).min(margin);
        if sky_edge > -2.0 * self.pixel {
            let height = (v / HORIZON).clamp(0.0, 1.0);
            let cloud = self.cloud_cover(u, v);
            let profile = self.wash_profile(sky_edge, 0.45, 0.006);
            let strokes = 0.7 + 0.6 * brush;
            let blue = (0.25 + 0.8 * (1.0 - height).powf(1.3)) * strokes * (1.0 - 0.92 * cloud);
            // A faint rim where the sky wash dried around the lifted cloud.
            let cloud_rim = 1.0 + 1.2 * cloud * (1.0 - cloud);
            washes.glaze_mix(
                &p.sky_cerulean,
                &p.sky_ultramarine,
                (1.0 - height).powf(0.7),
                blue * profile * granulation * cloud_rim * tide,
            );
            washes.glaze(
                &p.yellow_ochre,
                0.2 * smoothstep(0.55, 1.0, height) * profile,
            );
            // Grey bellies of the clouds, mottled, heavier lower down.
            let shade = self.cloud_shade.fbm(x * 3.0, v * 6.0, 5);
            let belly = cloud * smoothstep(0.4, 0.62, shade) * (0.5 + 2.0 * (v - 0.1).max(0.0));
            washes.glaze(&p.paynes_grey, 0.6 * belly * profile * granulation);
        }

        // --- Sea: two layered washes, darker towards the viewer, horizontal brush streaks and lifted crests.
        let sea_edge = (v - HORIZON).min(reserve).min(margin);
        if sea_edge > -2.0 * self.pixel {
            let depth = ((v - HORIZON) / (1.0 - HORIZON)).clamp(0.0, 1.0);
            let streak = self.sea_streak.fbm(x * 3.0, v * 90.0, 5);
            let crest = self.sea_crest.fbm(x * 6.0, v * 200.0, 3);
            let crest_patches =
                smoothstep(0.42, 0.62, self.sea_crest.fbm(x * 2.0 + 30.0, v * 5.0, 3));
            let lifted = 1.0
                - 0.8
                    * smoothstep(0.69, 0.77, crest)
                    * crest_patches
                    * smoothstep(0.03, 0.15, depth);
            let profile = self.wash_profile(sea_edge, 0.6, 0.004);
            let density = (0.45 + 0.75 * depth.powf(0.8)) * (0.65 + 0.7 * streak) * lifted;
            let hue = self.hue.fbm(x * 1.5, v * 6.0, 4);
            washes.glaze_mix(
                &p.sea_prussian,
                &p.sea_green,
                0.5 * smoothstep(0.3, 0.7, hue),
                density * profile * granulation,
            );
            // A greyer band just under the horizon, where the sea reflects the overcast.
            washes.glaze(
                &p.paynes_grey,
                0.35 * (1.0 - smoothstep(0.0, 0.15, depth)) * profile,
            );
            // Second layer over the foreground, laid after the first dried: its own wavy dried edge.
            let layer_line = 0.74 + 0.03 * (self.sea_streak.fbm(x * 1.5 + 9.0, 2.0, 4) - 0.5);
            let layer_edge = (v - layer_line + self.edge_jitter(u, v, 0.003)).min(sea_edge);
            let layer = self.wash_profile(layer_edge, 0.7, 0.004);
            washes.glaze(
                &p.sea_prussian,
                0.2 * layer * (0.6 + 0.8 * streak) * lifted * granulation,
            );
            // Reflections of the land masses: dark, streaky, fading away from the waterline.
            let reflection = self.reflection(u, v) * (0.5 + streak) * lifted;
            washes.glaze_mix(&p.hookers_green, &p.sea_prussian, 0.5, reflection * profile);
        }

        // --- Far island: one pale blue-grey wash.
        if land.far > -2.0 * self.pixel {
            let profile = self.wash_profile(land.far.min(margin), 0.7, 0.003);
            washes.glaze_mix(
                &p.paynes_grey,
                &p.sky_ultramarine,
                0.3,
                0.42 * profile * granulation,
            );
        }

        // --- Middle headland: greens muted by distance (more grey, less pigment), a dark shaded cliff face.
        if land.middle > -2.0 * self.pixel {
            let edge = land.middle.min(margin);
            let profile = self.wash_profile(edge, 0.55, 0.004);
            let hue = self.hue.fbm(x * 4.0, v * 4.0, 4);
            let below_top = v - self.middle_top(u);
            let slope_strokes = self.brush.fbm(x * 5.0 - v * 3.0, v * 14.0, 4);
            washes.glaze_mix(
                &p.sap_green,
                &p.yellow_green,
                hue,
                (0.5 + 0.4 * slope_strokes) * profile * tide,
            );
            washes.glaze(&p.paynes_grey, 0.3 * profile * granulation);
            // Lower slopes in the shadow of the ridge.
            let shadow_edge = below_top - 0.06 - 0.06 * self.brush.fbm(x * 5.0, 8.8, 3)
                + self.edge_jitter(u, v, 0.004);
            let shadow = self.wash_profile(shadow_edge.min(edge), 0.5, 0.004);
            washes.glaze_mix(
                &p.hookers_green,
                &p.paynes_grey,
                0.4,
                (0.25 + 0.2 * slope_strokes) * shadow,
            );
            let face_depth = self.horizontal(u - self.middle_face(v));
            let (rock, ledge) =
                self.rock_weight(face_depth, below_top, Self::MIDDLE_BASE - v, u, v, 0.7);
            washes.glaze_mix(
                &p.sepia,
                &p.paynes_grey,
                0.6,
                0.75 * rock * profile * granulation,
            );
            washes.glaze(&p.sap_green, 0.4 * ledge * profile);
        }

        // --- Sea stacks: dark basalt with a green cap.
        if land.stacks > -2.0 * self.pixel {
            let profile = self.wash_profile(land.stacks.min(margin), 0.5, 0.003);
            let cap = 1.0 - smoothstep(0.008, 0.025, v - self.stack_top(u));
            let ledge = self.strata_ledge(u, v);
            washes.glaze_mix(
                &p.sepia,
                &p.paynes_grey,
                0.55,
                (0.95 - 0.35 * ledge) * (1.0 - 0.5 * cap) * profile * granulation,
            );
            washes.glaze(&p.sap_green, (0.7 * cap + 0.3 * ledge) * profile);
        }

        // --- Near headland: sunlit grass shoulder, darker slope, the basalt sea cliff in shade.
        if land.near > -2.0 * self.pixel {
            let edge = land.near.min(margin);
            let profile = self.wash_profile(edge, 0.5, 0.005);
            let hue = self.hue.fbm(x * 3.0 + 5.0, v * 3.0, 5);
            let below_top = v - self.near_top(u);
            let slope_strokes = self.brush.fbm(x * 4.0 + v * 6.0, v * 16.0 - x * 2.0, 5);
            let grass = (0.6 + 0.55 * slope_strokes) * profile * tide;
            washes.glaze_mix(
                &p.yellow_green,
                &p.sap_green,
                smoothstep(0.3, 0.7, hue),
                grass,
            );
            washes.glaze(&p.yellow_ochre, 0.3 * (1.0 - hue) * profile);
            // Second, darker glaze lower down the slope, with its own dried edge.
            let shadow_edge = below_top - 0.09 - 0.08 * self.brush.fbm(x * 6.0, 3.3, 3)
                + self.edge_jitter(u, v, 0.004);
            let shadow = self.wash_profile(shadow_edge.min(edge), 0.5, 0.004);
            washes.glaze(&p.hookers_green, (0.3 + 0.3 * slope_strokes) * shadow);
            let face_depth = self.horizontal(self.near_face(v) - u);
            let (rock, ledge) =
                self.rock_weight(face_depth, below_top, self.near_base(u) - v, u, v, 1.0);
            washes.glaze_mix(
                &p.sepia,
                &p.paynes_grey,
                0.45,
                1.1 * rock * profile * granulation,
            );
            washes.glaze(&p.sky_ultramarine, 0.3 * rock * profile);
            washes.glaze(&p.sap_green, 0.5 * ledge * profile);
        }

        // Blooms move pigment, they do not add any; the paper margin stays clean.
        let bloom = if margin > 0.0 {
            self.bloom_factor(u, v)
        } else {
            1.0
        };
        let paper_grain = 1.0 - 0.06 * (grain - 0.5);
        std::array::from_fn(|c| self.paper[c] * paper_grain * (-washes.absorbance[c] * bloom).exp())
    }

    /// Horizontal basalt layering: 1 on the thin grassy ledges between lava flows, 0 on the rock between them.
    fn strata_ledge(&self, u: f64, v: f64) -> f64 {
        let wobble = self.strata.fbm(self.horizontal(u) * 3.0, v * 3.0, 4);
        let phase = (v * 32.0 + 5.0 * wobble) * std::f64::consts::TAU;
        smoothstep(0.6, 0.95, phase.sin())
    }

    /// Weights (0–1) of the dark rock wash and of the green ledges on a headland's cliff: rock within a noisy
    /// depth of the face and along the waterline, none on the grass shoulder; ledges interrupt the rock.
    fn rock_weight(
        &self,
        face_depth: f64,
        below_top: f64,
        above_base: f64,
        u: f64,
        v: f64,
        scale: f64,
    ) -> (f64, f64) {
        let x = self.horizontal(u);
        let reach = scale
            * (0.02 + 0.1 * smoothstep(0.0, 0.3, below_top))
            * (0.5 + 1.0 * self.strata.fbm(x * 5.0, v * 12.0, 4));
        let face = smoothstep(0.0, 0.5 * self.pixel + 0.004, reach - face_depth);
        let shore = smoothstep(
            0.0,
            0.006,
            scale * 0.05 * (0.5 + self.strata.fbm(x * 14.0, 1.7, 3)) - above_base,
        );
        let cliff = face.max(shore) * smoothstep(0.005, 0.03, below_top);
        let ledge = self.strata_ledge(u, v)
            * smoothstep(0.35, 0.6, self.strata.fbm(x * 9.0 + 3.0, v * 20.0, 3));
        (cliff * (1.0 - 0.75 * ledge), cliff * ledge)
    }

    /// Density of the land's reflection in the sea at (u, v).
    fn reflection(&self, u: f64, v: f64) -> f64 {
        let fade = |below: f64, length: f64| {
            if below > 0.0 {
                (-below / length).exp()
            } else {
                0.0
            }
        };
        let near = if u < self.near_face(self.near_base(u)) {
            fade(v - self.near_base(u), 0.05)
        } else {
            0.0
        };
        let middle = if u > self.middle_face(Self::MIDDLE_BASE) {
            fade(v - Self::MIDDLE_BASE, 0.03)
        } else {
            0.0
        };
        let stacks = Self::STACKS
            .iter()
            .map(|&(centre, half_width, _)| {
                let across = self.horizontal((u - centre).abs());
                if across < 1.1 * half_width {
                    fade(v - Self::STACK_BASE, 0.035)
                } else {
                    0.0
                }
            })
            .fold(0.0, f64::max);
        0.9 * near + 0.5 * middle + 0.6 * stacks
    }
}

/// A watercolour of a Faroese coast, `width` × `height` px, deterministic for a given `seed`.
///
/// The composition is fixed (sky over a horizon at 52 % of the height; a steep green headland on the left with a
/// dark basalt sea cliff; a paler headland on the right; two sea stacks and a far island in the gap between them;
/// the sea in front); the seed moves every brush mark, cloud, wash edge, bloom and grain of paper. See the module
/// documentation for the model.
pub fn faroe_landscape(width: u32, height: u32, seed: u64) -> Result<RgbImage, AssetError> {
    check_size(width, height)?;
    let painting = Painting::new(width, height, seed);
    let mut image = RgbImage::new(width, height);
    let (w, h) = (f64::from(width), f64::from(height));
    image
        .as_mut()
        .par_chunks_mut(width as usize * 3)
        .enumerate()
        .for_each(|(y, row)| {
            let v = (y as f64 + 0.5) / h;
            for (x, pixel) in row.chunks_exact_mut(3).enumerate() {
                let u = (x as f64 + 0.5) / w;
                pixel.copy_from_slice(&linear_to_srgb8(painting.reflectance(u, v)));
            }
        });
    Ok(image)
}

/// Writes `faroe_flag.png` (1100 × 800) and `faroe_landscape.png` (1024 × 1024, seed 1) into `dir`, creating it
/// if needed.
pub fn write_assets(dir: &Path) -> Result<(), AssetError> {
    std::fs::create_dir_all(dir).map_err(|source| AssetError::CreateDir {
        path: dir.to_path_buf(),
        source,
    })?;
    let flag = faroe_flag(FLAG_ASSET_SIZE.0)?;
    save_png(&flag, &dir.join(FLAG_FILE_NAME))?;
    let (width, height) = LANDSCAPE_ASSET_SIZE;
    let landscape = faroe_landscape(width, height, LANDSCAPE_ASSET_SEED)?;
    save_png(&landscape, &dir.join(LANDSCAPE_FILE_NAME))
}

fn save_png(image: &RgbImage, path: &Path) -> Result<(), AssetError> {
    sheer_slab::render::save_image_file(image, path, image::ImageFormat::Png).map_err(|source| {
        AssetError::Write {
            path: path.to_path_buf(),
            source,
        }
    })
}

#[cfg(test)]
mod tests {
    //! The generators against the flag act's construction and the painting's composition; the committed files
    //! against the generators.

    use super::*;

    const WORKSPACE_ASSETS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets");

    fn pixel(image: &RgbImage, x: u32, y: u32) -> [u8; 3] {
        image.get_pixel(x, y).0
    }

    #[test]
    fn flag_bands_fall_on_the_construction_units_at_50_px_per_unit() {
        let flag = faroe_flag(1100).unwrap();
        assert_eq!(flag.dimensions(), (1100, 800));
        // Along the length, in the top white field's row 100: 6 | 1 | 2 | 1 | 12 units of 50 px.
        let row = 100;
        for (x, expected) in [
            (0, FLAG_WHITE),
            (299, FLAG_WHITE),
            (300, FLAG_BLUE),
            (349, FLAG_BLUE),
            (350, FLAG_RED),
            (449, FLAG_RED),
            (450, FLAG_BLUE),
            (499, FLAG_BLUE),
            (500, FLAG_WHITE),
            (1099, FLAG_WHITE),
        ] {
            assert_eq!(pixel(&flag, x, row), expected, "column {x}");
        }
        // Along the height, in the hoist's white column 100: 6 | 1 | 2 | 1 | 6 units of 50 px.
        let column = 100;
        for (y, expected) in [
            (0, FLAG_WHITE),
            (299, FLAG_WHITE),
            (300, FLAG_BLUE),
            (349, FLAG_BLUE),
            (350, FLAG_RED),
            (449, FLAG_RED),
            (450, FLAG_BLUE),
            (499, FLAG_BLUE),
            (500, FLAG_WHITE),
            (799, FLAG_WHITE),
        ] {
            assert_eq!(pixel(&flag, column, y), expected, "row {y}");
        }
        // Where the bands cross, red wins over blue and blue over white.
        assert_eq!(pixel(&flag, 400, 400), FLAG_RED);
        assert_eq!(pixel(&flag, 325, 325), FLAG_BLUE);
        assert_eq!(pixel(&flag, 400, 325), FLAG_RED);
    }

    #[test]
    fn flag_colour_areas_match_the_construction() {
        // At 50 px per unit every pixel is a pure colour and the areas are exact: red = column + row − square.
        let flag = faroe_flag(1100).unwrap();
        let mut counts = [0usize; 3];
        for p in flag.pixels() {
            let index = [FLAG_WHITE, FLAG_BLUE, FLAG_RED]
                .iter()
                .position(|c| *c == p.0)
                .unwrap_or_else(|| panic!("pixel {:?} is not a flag colour", p.0));
            counts[index] += 1;
        }
        let red = 100 * 800 + 100 * 1100 - 100 * 100;
        let cross = 200 * 800 + 200 * 1100 - 200 * 200;
        assert_eq!(counts, [1100 * 800 - cross, cross - red, red]);
    }

    #[test]
    fn flag_proportions_are_8_to_11() {
        assert_eq!(flag_height(11), 8);
        assert_eq!(flag_height(1100), 800);
        for width in 22..3000u32 {
            let height = flag_height(width);
            let exact = f64::from(width) * 8.0 / 11.0;
            assert!(
                (f64::from(height) - exact).abs() <= 0.5,
                "width {width}: height {height}, 8/11 of it {exact}"
            );
        }
    }

    #[test]
    fn flag_narrower_than_its_22_units_is_refused() {
        assert!(matches!(
            faroe_flag(21),
            Err(AssetError::FlagTooNarrow { width: 21 })
        ));
        assert!(matches!(
            faroe_flag(0),
            Err(AssetError::FlagTooNarrow { width: 0 })
        ));
        assert_eq!(faroe_flag(22).unwrap().dimensions(), (22, 16));
        assert!(matches!(
            faroe_flag(u32::MAX),
            Err(AssetError::ImageTooLarge { .. })
        ));
    }

    #[test]
    fn anti_aliased_flag_keeps_each_colours_area() {
        // At 37 px (not a multiple of 22) edge pixels mix colours by area in linear light, so the image's mean
        // linear colour equals the area-weighted mean of the three colours up to 8-bit rounding: ≤ 0.5/255 in
        // sRGB, times the sRGB decoding's steepest slope, 2.4/1.055 ≈ 2.3, so ≤ 1.2/255 in linear light.
        let width = 37;
        let flag = faroe_flag(width).unwrap();
        let height = flag.height();
        let (w, h) = (f64::from(width), f64::from(height));
        let units_x = 22.0 / w;
        let units_y = 16.0 / h;
        // Exact areas in the image's own (rounded-height) frame, in construction units scaled to pixels.
        let (red_x, cross_x) = (2.0 / units_x, 4.0 / units_x);
        let (red_y, cross_y) = (2.0 / units_y, 4.0 / units_y);
        let red = red_x * h + red_y * w - red_x * red_y;
        let cross = cross_x * h + cross_y * w - cross_x * cross_y;
        let area = w * h;
        let expected: [f64; 3] = std::array::from_fn(|c| {
            ((area - cross) * srgb8_to_linear(FLAG_WHITE)[c]
                + (cross - red) * srgb8_to_linear(FLAG_BLUE)[c]
                + red * srgb8_to_linear(FLAG_RED)[c])
                / area
        });
        let mut mean = [0.0; 3];
        for p in flag.pixels() {
            let linear = srgb8_to_linear(p.0);
            for c in 0..3 {
                mean[c] += linear[c] / area;
            }
        }
        for c in 0..3 {
            assert!(
                (mean[c] - expected[c]).abs() < 2.0 / 255.0,
                "channel {c}: mean {} expected {}",
                mean[c],
                expected[c]
            );
        }
        // And some pixels are genuinely mixed (the edges are anti-aliased, not snapped).
        let pure = [FLAG_WHITE, FLAG_BLUE, FLAG_RED];
        assert!(flag.pixels().any(|p| !pure.contains(&p.0)));
    }

    /// The pixels of a `size`-px square around (u, v).
    fn patch(image: &RgbImage, u: f64, v: f64, size: u32) -> impl Iterator<Item = [u8; 3]> + '_ {
        let (cx, cy) = (
            (u * f64::from(image.width())) as u32,
            (v * f64::from(image.height())) as u32,
        );
        (cy - size / 2..cy + size / 2)
            .flat_map(move |y| (cx - size / 2..cx + size / 2).map(move |x| pixel(image, x, y)))
    }

    /// Mean sRGB colour of a `size`-px square around (u, v).
    fn patch_mean(image: &RgbImage, u: f64, v: f64, size: u32) -> [f64; 3] {
        let mut sum = [0.0; 3];
        let mut n = 0.0;
        for p in patch(image, u, v, size) {
            for c in 0..3 {
                sum[c] += f64::from(p[c]);
            }
            n += 1.0;
        }
        sum.map(|s| s / n)
    }

    /// Standard deviation of the luminance over a `size`-px square around (u, v), of 255.
    fn luminance_spread(image: &RgbImage, u: f64, v: f64, size: u32) -> f64 {
        let values: Vec<f64> = patch(image, u, v, size)
            .map(|p| 0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2]))
            .collect();
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        (values.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / values.len() as f64).sqrt()
    }

    #[test]
    fn landscape_has_sky_cliffs_sea_and_paper_where_the_composition_puts_them() {
        let painting = faroe_landscape(512, 512, LANDSCAPE_ASSET_SEED).unwrap();
        let sky = patch_mean(&painting, 0.5, 0.08, 24);
        let headland = patch_mean(&painting, 0.15, 0.5, 24);
        let sea = patch_mean(&painting, 0.5, 0.85, 24);
        let paper = patch_mean(&painting, 0.5, 0.004, 2);
        assert!(sky[2] > sky[0] + 30.0 && sky[2] > sky[1], "sky {sky:?}");
        assert!(
            headland[1] > headland[0] && headland[1] > headland[2] + 20.0,
            "headland {headland:?}"
        );
        assert!(sea[2] > sea[0] + 30.0, "sea {sea:?}");
        let brightness = |c: [f64; 3]| c.iter().sum::<f64>();
        assert!(brightness(sea) < brightness(sky), "sea {sea:?} sky {sky:?}");
        assert!(paper.iter().all(|&c| c > 220.0), "paper margin {paper:?}");
    }

    #[test]
    fn landscape_washes_are_painterly_not_flat() {
        // A flat fill has zero spread; granulation, brush strokes and paper grain give every wash texture.
        let painting = faroe_landscape(512, 512, LANDSCAPE_ASSET_SEED).unwrap();
        for (name, u, v) in [
            ("sky", 0.5, 0.08),
            ("headland", 0.15, 0.5),
            ("sea", 0.5, 0.85),
        ] {
            let spread = luminance_spread(&painting, u, v, 32);
            assert!(spread > 2.0, "{name}: luminance spread {spread:.2} of 255");
        }
    }

    #[test]
    fn landscape_is_a_pure_function_of_size_and_seed_whatever_the_thread_count() {
        let one_thread = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| faroe_landscape(200, 150, 7).unwrap());
        let three_threads = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap()
            .install(|| faroe_landscape(200, 150, 7).unwrap());
        assert!(
            one_thread == three_threads,
            "thread count changed the painting"
        );
        let other_seed = faroe_landscape(200, 150, 8).unwrap();
        let differing = one_thread
            .pixels()
            .zip(other_seed.pixels())
            .filter(|(a, b)| a != b)
            .count();
        assert!(
            differing > 200 * 150 / 2,
            "another seed changed only {differing} of {} pixels",
            200 * 150
        );
    }

    #[test]
    fn landscape_of_zero_or_huge_size_is_refused() {
        assert!(matches!(
            faroe_landscape(0, 10, 1),
            Err(AssetError::EmptyImage { .. })
        ));
        assert!(matches!(
            faroe_landscape(10, 0, 1),
            Err(AssetError::EmptyImage { .. })
        ));
        assert!(matches!(
            faroe_landscape(100_000, 100_000, 1),
            Err(AssetError::ImageTooLarge { .. })
        ));
    }

    #[test]
    fn committed_assets_are_what_the_generators_make() {
        let load = |name: &str| {
            image::open(Path::new(WORKSPACE_ASSETS).join(name))
                .unwrap_or_else(|e| panic!("assets/{name}: {e}"))
                .to_rgb8()
        };
        // Compared with `==`, not `assert_eq!`, so that a failure does not print megabytes of pixels.
        assert!(
            load(FLAG_FILE_NAME) == faroe_flag(FLAG_ASSET_SIZE.0).unwrap(),
            "assets/{FLAG_FILE_NAME} is stale: run `sheer assets --out assets`"
        );
        let (width, height) = LANDSCAPE_ASSET_SIZE;
        assert!(
            load(LANDSCAPE_FILE_NAME)
                == faroe_landscape(width, height, LANDSCAPE_ASSET_SEED).unwrap(),
            "assets/{LANDSCAPE_FILE_NAME} is stale: run `sheer assets --out assets`"
        );
    }

    #[test]
    fn write_assets_reports_an_unwritable_folder() {
        // A folder cannot be created below a regular file.
        let file = std::env::temp_dir().join(format!("sheer-assets-test-{}", std::process::id()));
        std::fs::write(&file, b"not a folder").unwrap();
        let result = write_assets(&file.join("inside"));
        std::fs::remove_file(&file).unwrap();
        assert!(
            matches!(result, Err(AssetError::CreateDir { .. })),
            "{result:?}"
        );
    }
}
