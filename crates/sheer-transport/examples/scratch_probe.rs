//! Temporary probe (deleted before hand-off).
use sheer_transport::{AllOrdersTable, SlabSolver, TableSpec};
fn main() {
    let table = AllOrdersTable::generate(TableSpec { tau_count: 13, log10_tau_min: 0.0, log10_tau_max: 1.0, ..TableSpec::default() }).unwrap();
    let spec: TableSpec = table.spec();
    let node_tau = |t: f64| 10f64.powf(spec.log10_tau_min + t / (spec.tau_count - 1) as f64 * (spec.log10_tau_max - spec.log10_tau_min));
    let node_alb = |a: f64, tau1: f64| { let w = a / (spec.albedo_count - 1) as f64; let beta = 1.1 * tau1.ln_1p(); let s = (beta * w).exp_m1() / beta.exp_m1(); 1.0 - s * s };
    let node_mu = |k: f64| { let x = k / (spec.cosine_count - 1) as f64; x * x };
    for axis in 1..2 {
        let mut worst = [0.0f64; 4];
        let mut at = [(0.0,0.0,0.0,0.0); 2];
        for t in [2.0, 6.0, 10.0, 11.0] {
            for a in [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 7.0, 9.0] {
                for k in [1.0, 4.0, 10.0, 15.0] {
                    for j in [0.0, 4.0, 10.0, 15.0] {
                        let (mut tt, mut aa, mut kk, mut jj) = (t, a, k, j);
                        match axis { 0 => tt += 0.5, 1 => aa += 0.5, 2 => kk += 0.5, _ => jj += 0.5 }
                        let (tau1, albedo, mu0, mu) = (node_tau(tt), node_alb(aa, node_tau(tt.round())), node_mu(kk), node_mu(jj));
                        let s = SlabSolver::new(tau1, albedo).unwrap().solve(mu0).unwrap();
                        for side in 0..2 {
                            let (e, em, ap, apm) = if side == 0 {
                                (s.reflected_radiance(mu).unwrap(), s.multiple_reflected_radiance(mu).unwrap(), table.reflected_radiance(tau1, albedo, mu0, mu).unwrap(), table.multiple_reflected_radiance(tau1, albedo, mu0, mu).unwrap())
                            } else {
                                (s.transmitted_radiance(mu).unwrap(), s.multiple_transmitted_radiance(mu).unwrap(), table.transmitted_radiance(tau1, albedo, mu0, mu).unwrap(), table.multiple_transmitted_radiance(tau1, albedo, mu0, mu).unwrap())
                            };
                            let et = ((ap - e) / e).abs();
                            if et > worst[2 * side] { worst[2 * side] = et; at[side] = (tau1, albedo, mu0, mu); }
                            worst[2 * side + 1] = worst[2 * side + 1].max(((apm - em) / em).abs());
                        }
                    }
                }
            }
        }
        println!("axis {axis}: refl total {:.2e} ms {:.2e} at {:?} | trans total {:.2e} ms {:.2e} at {:?}", worst[0], worst[1], at[0], worst[2], worst[3], at[1]);
    }
}
