//! Gauss–Legendre quadrature rules (nodes by Newton iteration on the Legendre recurrence), single and
//! composite, used for the angular integrals (fluxes, the H-function) and for the `u`-representation of
//! the E1 kernel in [`crate::slab`].

/// Nodes and weights of the `n`-point Gauss–Legendre rule on `[a, b]`, exact for polynomials of degree
/// `2n − 1`. Nodes are returned in increasing order.
pub fn gauss_legendre(points: usize, a: f64, b: f64) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = vec![0.0; points];
    let mut weights = vec![0.0; points];
    let n = points as f64;
    let half_length = 0.5 * (b - a);
    let midpoint = 0.5 * (b + a);
    for i in 0..points.div_ceil(2) {
        // Tricomi's initial guess for the i-th root of P_n, then Newton to machine precision.
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n + 0.5)).cos();
        for _ in 0..100 {
            let (value, slope) = legendre_derivative(points, x);
            let step = value / slope;
            x -= step;
            if step.abs() < 1.0e-16 {
                break;
            }
        }
        // Weight from P_n' at the converged root (not at the previous iterate).
        let derivative = legendre_derivative(points, x).1;
        let weight = 2.0 / ((1.0 - x * x) * derivative * derivative);
        nodes[i] = midpoint - half_length * x;
        nodes[points - 1 - i] = midpoint + half_length * x;
        weights[i] = half_length * weight;
        weights[points - 1 - i] = half_length * weight;
    }
    (nodes, weights)
}

/// `(P_n(x), P_n'(x))` by the three-term recurrence.
fn legendre_derivative(order: usize, x: f64) -> (f64, f64) {
    let (mut previous, mut current) = (1.0, x);
    for k in 2..=order {
        let k = k as f64;
        let next = ((2.0 * k - 1.0) * x * current - (k - 1.0) * previous) / k;
        previous = current;
        current = next;
    }
    if order == 0 {
        return (1.0, 0.0);
    }
    let n = order as f64;
    (current, n * (x * current - previous) / (x * x - 1.0))
}

/// Composite Gauss–Legendre rule: `points` nodes on each panel between consecutive `breaks`
/// (which must increase). Returns all nodes (increasing) and weights.
pub fn composite_gauss_legendre(breaks: &[f64], points: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = Vec::with_capacity(points * breaks.len());
    let mut weights = Vec::with_capacity(points * breaks.len());
    for pair in breaks.windows(2) {
        let (x, w) = gauss_legendre(points, pair[0], pair[1]);
        nodes.extend(x);
        weights.extend(w);
    }
    (nodes, weights)
}

/// Panel breaks on `[0, 1]` refined geometrically towards 0 (`0, 10^{−decades}, …, 0.1, 1`): angular
/// integrands here behave like `μ ln μ` at grazing angles, which a uniform rule resolves poorly.
pub fn graded_unit_breaks(decades: u32) -> Vec<f64> {
    let mut breaks = vec![0.0];
    for k in (0..decades).rev() {
        breaks.push(10f64.powi(-(k as i32 + 1)));
    }
    breaks.push(1.0);
    breaks
}
