//! The cloth as plain data: particles, triangles, springs and pins, built from a grid or any mesh.
//!
//! Masses are lumped from the triangles: each triangle gives a third of `areal_density × area` to each of
//! its corners, so the total mass is exactly `areal_density × surface area` for any tessellation.

use std::collections::HashMap;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::error::ModelError;

/// Which family a spring belongs to; each family has its own [`SpringParams`](crate::SpringParams).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpringKind {
    /// Along the cloth's edges: grid neighbours in a row or column, or a mesh's triangle edges.
    Stretch,
    /// Across a grid cell's diagonals, resisting in-plane shearing (grids only).
    Shear,
    /// Skipping one particle on a grid, or joining the far corners of two triangles that share an
    /// edge on a mesh: resists folding.
    Bend,
}

/// A spring (or distance constraint) between particles `a` and `b`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spring {
    /// Index of the first end's particle.
    pub a: u32,
    /// Index of the second end's particle.
    pub b: u32,
    /// The family, whose [`SpringParams`](crate::SpringParams) set its stiffness and damping.
    pub kind: SpringKind,
    /// Rest length, m.
    pub rest_length: f64,
}

/// A rectangular W×H grid of particles, hung in the x–y plane: columns run along +x from `origin`,
/// rows run down along −y, so row 0 is the top edge and column 0 the hoist (pole) edge of a flag.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GridSpec {
    /// Particles per row (W ≥ 2).
    pub columns: usize,
    /// Particles per column (H ≥ 2).
    pub rows: usize,
    /// Size along x, m.
    pub width: f64,
    /// Size along y, m.
    pub height: f64,
    /// Mass per unit area, kg/m² (fabric: 0.1–0.3).
    pub areal_density: f64,
    /// Position of the top-left particle (row 0, column 0), m.
    pub origin: DVec3,
}

impl Default for GridSpec {
    /// The default flag: the Faroe flag's 8:11 proportions at 1.1 m × 0.8 m, 64 × 46 particles (square
    /// cells of about 1.75 cm), 0.2 kg/m² (a light polyester flag fabric).
    fn default() -> Self {
        GridSpec {
            columns: 64,
            rows: 46,
            width: 1.1,
            height: 0.8,
            areal_density: 0.2,
            origin: DVec3::new(0.0, 0.8, 0.0),
        }
    }
}

/// Grid shape of a cloth built by [`ClothModel::grid`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct GridShape {
    /// Particles per row (W).
    pub columns: usize,
    /// Particles per column (H).
    pub rows: usize,
}

impl GridShape {
    /// Particle index of (row, column).
    pub fn index(&self, row: usize, column: usize) -> usize {
        row * self.columns + column
    }

    /// The grid's springs as `(a, b, kind)`, particle by particle in row order: stretch to the right and
    /// down, the two shear diagonals of the cell below-right (`a` top left or top right), and bending to
    /// the particle two to the right and two down.
    pub fn spring_pairs(&self) -> Vec<(usize, usize, SpringKind)> {
        let (columns, rows) = (self.columns, self.rows);
        let mut pairs = Vec::new();
        for row in 0..rows {
            for column in 0..columns {
                let here = self.index(row, column);
                if column + 1 < columns {
                    pairs.push((here, self.index(row, column + 1), SpringKind::Stretch));
                }
                if row + 1 < rows {
                    pairs.push((here, self.index(row + 1, column), SpringKind::Stretch));
                }
                if column + 1 < columns && row + 1 < rows {
                    let diagonal = self.index(row + 1, column + 1);
                    pairs.push((here, diagonal, SpringKind::Shear));
                    let anti_diagonal = (self.index(row, column + 1), self.index(row + 1, column));
                    pairs.push((anti_diagonal.0, anti_diagonal.1, SpringKind::Shear));
                }
                if column + 2 < columns {
                    pairs.push((here, self.index(row, column + 2), SpringKind::Bend));
                }
                if row + 2 < rows {
                    pairs.push((here, self.index(row + 2, column), SpringKind::Bend));
                }
            }
        }
        pairs
    }

    /// The grid's triangulation: two triangles per cell, cells row by row, each
    /// `[top left, bottom left, bottom right]` then `[top left, bottom right, top right]`,
    /// counter-clockwise seen from +z (rows go down along −y). The simulator's row-wise wind pass relies
    /// on this order.
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        let (columns, rows) = (self.columns, self.rows);
        let mut triangles =
            Vec::with_capacity(2 * columns.saturating_sub(1) * rows.saturating_sub(1));
        for row in 0..rows.saturating_sub(1) {
            for column in 0..columns.saturating_sub(1) {
                let top_left = self.index(row, column) as u32;
                let top_right = self.index(row, column + 1) as u32;
                let bottom_left = self.index(row + 1, column) as u32;
                let bottom_right = self.index(row + 1, column + 1) as u32;
                triangles.push([top_left, bottom_left, bottom_right]);
                triangles.push([top_left, bottom_right, top_right]);
            }
        }
        triangles
    }
}

/// Particles, triangles, springs and pins: everything the simulator needs besides [`SimParams`](crate::SimParams).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClothModel {
    /// Rest positions, m.
    pub positions: Vec<DVec3>,
    /// Lumped particle masses, kg.
    pub masses: Vec<f64>,
    /// Triangles (for wind and rendering), counter-clockwise seen from +z on grids.
    pub triangles: Vec<[u32; 3]>,
    /// The springs of every family (distance constraints for the position-based methods).
    pub springs: Vec<Spring>,
    /// Pinned particles follow their pin targets instead of the dynamics.
    pub pinned: Vec<bool>,
    /// Present when the cloth was built by [`ClothModel::grid`].
    pub grid: Option<GridShape>,
}

impl ClothModel {
    /// A W×H particle grid (see [`GridSpec`]) with stretch, shear and bending springs.
    pub fn grid(spec: &GridSpec) -> Result<ClothModel, ModelError> {
        let GridSpec {
            columns,
            rows,
            width,
            height,
            areal_density,
            origin,
        } = *spec;
        if columns < 2 || rows < 2 {
            return Err(ModelError::GridTooSmall { columns, rows });
        }
        // Springs and triangles store particle indices as u32.
        if columns
            .checked_mul(rows)
            .is_none_or(|particles| particles > u32::MAX as usize)
        {
            return Err(ModelError::GridTooLarge { columns, rows });
        }
        for (name, value) in [("width", width), ("height", height)] {
            if !(value.is_finite() && value > 0.0) {
                return Err(ModelError::InvalidDimension { name, value });
            }
        }
        check_density(areal_density)?;
        for (i, c) in origin.to_array().into_iter().enumerate() {
            if !c.is_finite() {
                return Err(ModelError::InvalidDimension {
                    name: ["origin.x", "origin.y", "origin.z"][i],
                    value: c,
                });
            }
        }
        let shape = GridShape { columns, rows };
        let dx = width / (columns - 1) as f64;
        let dy = height / (rows - 1) as f64;
        let mut positions = Vec::with_capacity(columns * rows);
        for row in 0..rows {
            for column in 0..columns {
                positions.push(origin + DVec3::new(column as f64 * dx, -(row as f64) * dy, 0.0));
            }
        }
        let triangles = shape.triangles();
        let springs = shape
            .spring_pairs()
            .into_iter()
            .map(|(a, b, kind)| Spring {
                a: a as u32,
                b: b as u32,
                kind,
                rest_length: positions[a].distance(positions[b]),
            })
            .collect();
        let masses = lumped_masses(&positions, &triangles, areal_density)?;
        Ok(ClothModel {
            pinned: vec![false; positions.len()],
            positions,
            masses,
            triangles,
            springs,
            grid: Some(shape),
        })
    }

    /// A cloth from any indexed triangle mesh: stretch springs on the edges, bending springs between the
    /// far corners of every pair of triangles sharing an edge, no shear springs (the triangle edges
    /// already resist shear).
    pub fn from_triangle_mesh(
        positions: &[DVec3],
        indices: &[u32],
        areal_density: f64,
    ) -> Result<ClothModel, ModelError> {
        if indices.is_empty() || positions.is_empty() {
            return Err(ModelError::EmptyMesh);
        }
        if !indices.len().is_multiple_of(3) {
            return Err(ModelError::IndexCountNotMultipleOf3(indices.len()));
        }
        check_density(areal_density)?;
        check_positions(positions)?;
        let triangles: Vec<[u32; 3]> = indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        for (t, tri) in triangles.iter().enumerate() {
            check_triangle_indices(t, tri, positions.len())?;
        }
        let masses = lumped_masses(positions, &triangles, areal_density)?;
        // Edge → the far corners of the triangles that share it, in triangle order (deterministic).
        let mut edge_opposites: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        let mut edge_order: Vec<(u32, u32)> = Vec::new();
        for tri in &triangles {
            for k in 0..3 {
                let (i, j, far) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
                let key = (i.min(j), i.max(j));
                let entry = edge_opposites.entry(key).or_default();
                if entry.is_empty() {
                    edge_order.push(key);
                }
                entry.push(far);
            }
        }
        let mut springs = Vec::new();
        let mut bend_seen = std::collections::HashSet::new();
        for key in &edge_order {
            springs.push(Spring {
                a: key.0,
                b: key.1,
                kind: SpringKind::Stretch,
                rest_length: positions[key.0 as usize].distance(positions[key.1 as usize]),
            });
        }
        for key in &edge_order {
            let far = &edge_opposites[key];
            for x in 0..far.len() {
                for y in x + 1..far.len() {
                    let (p, q) = (far[x].min(far[y]), far[x].max(far[y]));
                    let rest_length = positions[p as usize].distance(positions[q as usize]);
                    if p != q && rest_length > 0.0 && bend_seen.insert((p, q)) {
                        springs.push(Spring {
                            a: p,
                            b: q,
                            kind: SpringKind::Bend,
                            rest_length,
                        });
                    }
                }
            }
        }
        Ok(ClothModel {
            positions: positions.to_vec(),
            masses,
            triangles,
            springs,
            pinned: vec![false; positions.len()],
            grid: None,
        })
    }

    /// Particles joined by explicit springs, with no triangles (no wind): for spring–mass systems such
    /// as oscillators and strings.
    pub fn from_particles_and_springs(
        positions: &[DVec3],
        masses: &[f64],
        springs: &[Spring],
    ) -> Result<ClothModel, ModelError> {
        let model = ClothModel {
            positions: positions.to_vec(),
            masses: masses.to_vec(),
            triangles: Vec::new(),
            springs: springs.to_vec(),
            pinned: vec![false; positions.len()],
            grid: None,
        };
        model.validate()?;
        Ok(model)
    }

    /// Checks what [`Simulation::new`](crate::Simulation::new) relies on, for a model built or edited
    /// field by field or deserialised (the constructors above check it as they build): at least one
    /// particle, a mass and a pin flag per particle, finite positions, finite positive masses, triangles
    /// and springs that name existing particles, triangles that are not degenerate at rest, springs of
    /// two distinct particles with a finite positive rest length, and a grid shape of at least 2×2 that
    /// holds exactly the particles.
    pub fn validate(&self) -> Result<(), ModelError> {
        let particle_count = self.positions.len();
        if particle_count == 0 {
            return Err(ModelError::EmptyMesh);
        }
        check_length("masses", self.masses.len(), particle_count)?;
        check_length("pinned", self.pinned.len(), particle_count)?;
        check_positions(&self.positions)?;
        for (index, &mass) in self.masses.iter().enumerate() {
            if !(mass.is_finite() && mass > 0.0) {
                return Err(ModelError::InvalidMass { index, mass });
            }
        }
        for (t, tri) in self.triangles.iter().enumerate() {
            check_triangle_indices(t, tri, particle_count)?;
            healthy_triangle_area(&self.positions, t, *tri)?;
        }
        for (s, spring) in self.springs.iter().enumerate() {
            check_spring(s, spring, particle_count)?;
        }
        if let Some(GridShape { columns, rows }) = self.grid {
            if columns < 2 || rows < 2 {
                return Err(ModelError::GridTooSmall { columns, rows });
            }
            if columns.checked_mul(rows) != Some(particle_count) {
                return Err(ModelError::GridShapeMismatch {
                    columns,
                    rows,
                    particle_count,
                });
            }
        }
        Ok(())
    }

    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        self.positions.len()
    }

    /// Total mass, kg.
    pub fn total_mass(&self) -> f64 {
        self.masses.iter().sum()
    }

    /// Pins the given particles.
    pub fn pin(&mut self, indices: &[usize]) -> Result<&mut Self, ModelError> {
        let particle_count = self.positions.len();
        check_length("pinned", self.pinned.len(), particle_count)?;
        if let Some(&index) = indices.iter().find(|&&i| i >= particle_count) {
            return Err(ModelError::PinOutOfRange {
                index,
                particle_count,
            });
        }
        for &i in indices {
            self.pinned[i] = true;
        }
        Ok(self)
    }

    /// Pins the hoist edge of a grid flag (column 0, the pole side): `ClothModel::grid(&spec)?.with_hoist_pinned()?`.
    pub fn with_hoist_pinned(mut self) -> Result<Self, ModelError> {
        let shape = self.grid.ok_or(ModelError::NotAGrid)?;
        let hoist: Vec<usize> = (0..shape.rows).map(|row| shape.index(row, 0)).collect();
        self.pin(&hoist)?;
        Ok(self)
    }

    /// Pins the top edge of a grid (row 0): a hanging sheet or curtain.
    pub fn with_top_edge_pinned(mut self) -> Result<Self, ModelError> {
        let shape = self.grid.ok_or(ModelError::NotAGrid)?;
        let top: Vec<usize> = (0..shape.columns).collect();
        self.pin(&top)?;
        Ok(self)
    }

    /// Triangle indices as a flat list (for renderers and normal updaters).
    pub fn triangle_indices(&self) -> Vec<u32> {
        self.triangles.iter().flatten().copied().collect()
    }
}

fn check_density(areal_density: f64) -> Result<(), ModelError> {
    if areal_density.is_finite() && areal_density > 0.0 {
        Ok(())
    } else {
        Err(ModelError::InvalidDensity(areal_density))
    }
}

/// Whether the per-particle array `field` has `len` entries, one per particle.
pub(crate) fn check_length(
    field: &'static str,
    len: usize,
    particle_count: usize,
) -> Result<(), ModelError> {
    if len == particle_count {
        Ok(())
    } else {
        Err(ModelError::LengthMismatch {
            field,
            len,
            particle_count,
        })
    }
}

fn check_triangle_indices(
    triangle: usize,
    corners: &[u32; 3],
    vertex_count: usize,
) -> Result<(), ModelError> {
    match corners
        .iter()
        .find(|&&index| index as usize >= vertex_count)
    {
        Some(&index) => Err(ModelError::IndexOutOfRange {
            triangle,
            index,
            vertex_count,
        }),
        None => Ok(()),
    }
}

fn check_spring(index: usize, spring: &Spring, particle_count: usize) -> Result<(), ModelError> {
    if let Some(particle) = [spring.a, spring.b]
        .into_iter()
        .find(|&p| p as usize >= particle_count)
    {
        return Err(ModelError::SpringOutOfRange {
            spring: index,
            index: particle,
            particle_count,
        });
    }
    if spring.a == spring.b || !(spring.rest_length.is_finite() && spring.rest_length > 0.0) {
        return Err(ModelError::DegenerateSpring(index));
    }
    Ok(())
}

/// The area (m²) of triangle `t` at rest, or an error if it is degenerate: its area negligible against
/// its squared longest edge (a sliver or a collapsed triangle, not merely a small one: a fine mesh has
/// small but healthy triangles), or a corner repeated.
fn healthy_triangle_area(
    positions: &[DVec3],
    t: usize,
    [a, b, c]: [u32; 3],
) -> Result<f64, ModelError> {
    let (pa, pb, pc) = (
        positions[a as usize],
        positions[b as usize],
        positions[c as usize],
    );
    let area = 0.5 * (pb - pa).cross(pc - pa).length();
    let longest = (pb - pa)
        .length_squared()
        .max((pc - pb).length_squared())
        .max((pa - pc).length_squared());
    let healthy = area > 1e-9 * longest; // false for NaN too
    if !healthy || a == b || b == c || a == c {
        return Err(ModelError::DegenerateTriangle { triangle: t, area });
    }
    Ok(area)
}

fn check_positions(positions: &[DVec3]) -> Result<(), ModelError> {
    match positions.iter().position(|p| !p.is_finite()) {
        Some(vertex) => Err(ModelError::NonFinitePosition(vertex)),
        None => Ok(()),
    }
}

/// A third of each triangle's mass to each corner; rejects degenerate triangles and massless particles.
fn lumped_masses(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    areal_density: f64,
) -> Result<Vec<f64>, ModelError> {
    let mut masses = vec![0.0; positions.len()];
    for (t, &corners) in triangles.iter().enumerate() {
        let area = healthy_triangle_area(positions, t, corners)?;
        for i in corners {
            masses[i as usize] += areal_density * area / 3.0;
        }
    }
    if let Some(i) = masses.iter().position(|&m| m <= 0.0) {
        return Err(ModelError::MasslessParticle(i));
    }
    // A finite density over a huge area can still overflow.
    if let Some((index, &mass)) = masses.iter().enumerate().find(|(_, m)| !m.is_finite()) {
        return Err(ModelError::InvalidMass { index, mass });
    }
    Ok(masses)
}
