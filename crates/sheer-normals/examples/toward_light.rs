//! A 3 × 3-vertex flat sheet in the plane z = 0 with deliberately mixed triangle windings, lit by a
//! point light first above it, then below it: every normal is the exact plane normal, turned toward
//! the light. Then the per-fragment rule for an eye above the sheet.
//!
//! Run: `cargo run -p sheer-normals --release --example toward_light`

use glam::Vec3;
use sheer_normals::{Face, Light, NormalUpdater, NormalsError, lit_side_cosines};

fn main() -> Result<(), NormalsError> {
    let side = 3usize;
    let positions: Vec<Vec3> = (0..side * side)
        .map(|k| Vec3::new((k % side) as f32 * 0.5, (k / side) as f32 * 0.5, 0.0))
        .collect();
    let mut indices = Vec::new();
    for j in 0..side - 1 {
        for i in 0..side - 1 {
            let v = (j * side + i) as u32;
            let s = side as u32;
            // Alternate windings cell by cell: the result must not care.
            if (i + j) % 2 == 0 {
                indices.extend_from_slice(&[v, v + 1, v + s, v + 1, v + s + 1, v + s]);
            } else {
                indices.extend_from_slice(&[v, v + s, v + 1, v + 1, v + s, v + s + 1]);
            }
        }
    }

    let mut updater = NormalUpdater::new(positions.len(), &indices)?;
    let mut normals = vec![Vec3::ZERO; positions.len()];
    let eye = Vec3::new(0.5, 0.5, 3.0);
    for light_z in [2.0f32, -2.0] {
        let light_position = Vec3::new(0.5, 0.5, light_z);
        updater.update(
            &positions,
            &Light::Point {
                position: light_position,
            },
            &mut normals,
        )?;
        println!("point light at {light_position}:");
        for (vertex, (position, normal)) in positions.iter().zip(&normals).enumerate() {
            let side = lit_side_cosines(*normal, light_position - *position, eye - *position)?;
            println!(
                "  vertex {vertex} at {position}: normal {normal}, mu0 = {:.4}, mu = {:.4}, {}",
                side.mu0,
                side.mu,
                if side.face == Face::Lit {
                    "eye on lit side: eq. (7)"
                } else {
                    "eye on far side: eq. (8)"
                }
            );
        }
    }
    Ok(())
}
