use sheer_cloth::glam::DVec3;
use sheer_cloth::*;
fn main() {
    for per in [false] { for dens in [0.1, 0.2, 0.3] { for wind in [0.0, 4.0, 8.0, 12.0] {
    let spec = GridSpec { areal_density: dens, ..GridSpec::default() };
    let model = ClothModel::grid(&spec).unwrap().with_hoist_pinned().unwrap();
    let mut p = SimParams::default();
    p.wind.velocity = DVec3::new(wind, 0.0, wind/4.0);
    p.wind.per_substep = per;
    let mut sim = Simulation::new(model, p).unwrap();
    let mut worst = 0.0f64; let mut err = String::new();
    for _ in 0..600 { if let Err(e) = sim.step(1.0/60.0) { err = e.to_string(); break; } worst = worst.max(sim.max_strain(Some(SpringKind::Stretch))); }
    let st: Vec<f64> = sim.springs().iter().filter(|s| s.kind==SpringKind::Stretch).map(|s| sim.positions()[s.a as usize].distance(sim.positions()[s.b as usize])/s.rest_length-1.0).collect();
    let mean = st.iter().sum::<f64>()/st.len() as f64;
    let mut sorted = st.clone(); sorted.sort_by(|a,b| a.total_cmp(b));
    println!("per_substep {per} density {dens} wind {wind}: worst stretch {worst:.4} final mean {mean:.4} p99 {:.4} max {:.4} {err}", sorted[sorted.len()*99/100], sorted[sorted.len()-1]);
    }}}
}
