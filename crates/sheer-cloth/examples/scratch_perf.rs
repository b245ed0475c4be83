use sheer_cloth::glam::DVec3;
use sheer_cloth::*;
fn main() {
    for wind in [8.0, 10.0, 12.0, 16.0] { for per in [false, true] {
    let spec = GridSpec { areal_density: 0.1, ..GridSpec::default() };
    let model = ClothModel::grid(&spec).unwrap().with_hoist_pinned().unwrap();
    let mut p = SimParams::default();
    p.wind.velocity = DVec3::new(wind, 0.0, wind/4.0);
    p.wind.per_substep = per;
    let mut sim = Simulation::new(model, p).unwrap();
    let r = (0..600).try_for_each(|_| sim.step(1.0/60.0).map(|_| ()));
    println!("wind {wind} per_substep {per}: {:?}", r.map_err(|e| e.to_string()));
    }}
}
