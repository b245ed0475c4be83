use sheer_cloth::glam::DVec3;
use sheer_cloth::*;
fn main() {
    let v: usize = std::env::args().nth(1).unwrap().parse().unwrap();
    let frames: usize = std::env::args()
        .nth(2)
        .map(|s| s.parse().unwrap())
        .unwrap_or(100);
    let model = ClothModel::grid(&GridSpec::default())
        .unwrap()
        .with_hoist_pinned()
        .unwrap();
    let mut p = SimParams::default();
    p.wind.velocity = DVec3::new(6.0, 0.0, 1.0);
    match v {
        1 => p.wind.velocity = DVec3::ZERO,
        2 => {
            p.wind.velocity = DVec3::ZERO;
            p.shear.enabled = false;
            p.bend.enabled = false;
        }
        3 => {
            p.wind.per_substep = false;
        }
        _ => {}
    }
    let mut sim = Simulation::new(model, p).unwrap();
    for _ in 0..frames {
        sim.step(1.0 / 60.0).unwrap();
    }
}
