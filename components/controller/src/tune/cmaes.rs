//! Separable CMA-ES (Ros & Hansen 2008, "A simple modification in CMA-ES achieving
//! linear time and space complexity"): CMA-ES with a diagonal covariance.
//!
//! Why our own: the `cmaes` crate pulls nalgebra, rand and a plotting stack into the
//! controller for a ~100-line algorithm; the gait has ~13 loosely coupled parameters in
//! a normalised box, where the diagonal variant is the documented choice, and we need
//! bit-for-bit determinism per seed (our own SplitMix64 + Box-Muller).

/// Deterministic random numbers: SplitMix64 with Box-Muller normals.
#[derive(Debug, Clone)]
pub struct Rng {
    state: u64,
    spare: Option<f64>,
}

impl Rng {
    /// A generator for `seed`.
    pub fn new(seed: u64) -> Self {
        Self {
            state: seed ^ 0x9E37_79B9_7F4A_7C15,
            spare: None,
        }
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in \[0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal.
    pub fn normal(&mut self) -> f64 {
        if let Some(v) = self.spare.take() {
            return v;
        }
        let u1 = self.uniform().max(f64::MIN_POSITIVE);
        let u2 = self.uniform();
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (2.0 * std::f64::consts::PI * u2).sin_cos();
        self.spare = Some(r * s);
        r * c
    }
}

/// State of a separable CMA-ES minimising over R^n.
#[derive(Debug, Clone)]
pub struct SepCmaEs {
    /// Distribution mean.
    pub mean: Vec<f64>,
    /// Step size.
    pub sigma: f64,
    diag: Vec<f64>,
    p_sigma: Vec<f64>,
    p_c: Vec<f64>,
    weights: Vec<f64>,
    mu_eff: f64,
    c_sigma: f64,
    d_sigma: f64,
    c_c: f64,
    c_1: f64,
    c_mu: f64,
    chi_n: f64,
    generation: u32,
    /// Offspring per generation (lambda).
    pub lambda: usize,
}

/// One sampled candidate: `x = mean + sigma * sqrt(diag) * z`.
#[derive(Debug, Clone)]
pub struct Sample {
    /// Standard normal draw.
    pub z: Vec<f64>,
    /// The candidate.
    pub x: Vec<f64>,
}

impl SepCmaEs {
    /// Starts at `mean` with step size `sigma`; `lambda` = 0 takes the default
    /// 4 + 3 ln n.
    pub fn new(mean: Vec<f64>, sigma: f64, lambda: usize) -> Self {
        let n = mean.len() as f64;
        let lambda = if lambda == 0 {
            4 + (3.0 * n.ln()).floor() as usize
        } else {
            lambda.max(4)
        };
        let mu = lambda / 2;
        let raw: Vec<f64> = (0..mu)
            .map(|i| (mu as f64 + 0.5).ln() - ((i + 1) as f64).ln())
            .collect();
        let sum: f64 = raw.iter().sum();
        let weights: Vec<f64> = raw.iter().map(|w| w / sum).collect();
        let mu_eff = 1.0 / weights.iter().map(|w| w * w).sum::<f64>();
        let c_sigma = (mu_eff + 2.0) / (n + mu_eff + 5.0);
        let d_sigma = 1.0 + 2.0 * (((mu_eff - 1.0) / (n + 1.0)).sqrt() - 1.0).max(0.0) + c_sigma;
        let c_c = (4.0 + mu_eff / n) / (n + 4.0 + 2.0 * mu_eff / n);
        // Separable variant: learning rates scaled up by (n + 2) / 3.
        let sep = (n + 2.0) / 3.0;
        let c_1 = (sep * 2.0 / ((n + 1.3).powi(2) + mu_eff)).min(1.0);
        let c_mu = (sep * 2.0 * (mu_eff - 2.0 + 1.0 / mu_eff) / ((n + 2.0).powi(2) + mu_eff))
            .min(1.0 - c_1);
        let chi_n = n.sqrt() * (1.0 - 1.0 / (4.0 * n) + 1.0 / (21.0 * n * n));
        let dim = mean.len();
        Self {
            mean,
            sigma,
            diag: vec![1.0; dim],
            p_sigma: vec![0.0; dim],
            p_c: vec![0.0; dim],
            weights,
            mu_eff,
            c_sigma,
            d_sigma,
            c_c,
            c_1,
            c_mu,
            chi_n,
            generation: 0,
            lambda,
        }
    }

    /// Draws `lambda` candidates.
    pub fn ask(&self, rng: &mut Rng) -> Vec<Sample> {
        (0..self.lambda)
            .map(|_| {
                let z: Vec<f64> = (0..self.mean.len()).map(|_| rng.normal()).collect();
                let x = self
                    .mean
                    .iter()
                    .zip(&z)
                    .zip(&self.diag)
                    .map(|((m, z), d)| m + self.sigma * d.sqrt() * z)
                    .collect();
                Sample { z, x }
            })
            .collect()
    }

    /// Updates the distribution from the candidates and their costs (lower is better).
    pub fn tell(&mut self, samples: &[Sample], costs: &[f64]) {
        let n = self.mean.len();
        let mut order: Vec<usize> = (0..samples.len()).collect();
        order.sort_by(|&a, &b| costs[a].total_cmp(&costs[b]));
        let mut zw = vec![0.0; n];
        let mut yw = vec![0.0; n];
        let mut yy = vec![0.0; n];
        for (w, &k) in self.weights.iter().zip(&order) {
            for i in 0..n {
                let y = self.diag[i].sqrt() * samples[k].z[i];
                zw[i] += w * samples[k].z[i];
                yw[i] += w * y;
                yy[i] += w * y * y;
            }
        }
        self.generation += 1;
        let cs = (self.c_sigma * (2.0 - self.c_sigma) * self.mu_eff).sqrt();
        for i in 0..n {
            self.mean[i] += self.sigma * yw[i];
            self.p_sigma[i] = (1.0 - self.c_sigma) * self.p_sigma[i] + cs * zw[i];
        }
        let ps_norm = self.p_sigma.iter().map(|v| v * v).sum::<f64>().sqrt();
        let decay = 1.0 - (1.0 - self.c_sigma).powi(2 * self.generation as i32);
        let h_sigma = ps_norm / decay.sqrt() / self.chi_n < 1.4 + 2.0 / (n as f64 + 1.0);
        let cc = (self.c_c * (2.0 - self.c_c) * self.mu_eff).sqrt();
        for i in 0..n {
            self.p_c[i] = (1.0 - self.c_c) * self.p_c[i] + if h_sigma { cc * yw[i] } else { 0.0 };
            self.diag[i] = (1.0 - self.c_1 - self.c_mu) * self.diag[i]
                + self.c_1 * self.p_c[i] * self.p_c[i]
                + self.c_mu * yy[i];
        }
        self.sigma *= ((self.c_sigma / self.d_sigma) * (ps_norm / self.chi_n - 1.0)).exp();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn minimises_a_shifted_ellipsoid_deterministically() {
        let f = |x: &[f64]| -> f64 {
            x.iter()
                .enumerate()
                .map(|(i, v)| (i as f64 + 1.0) * (v - 0.3).powi(2))
                .sum()
        };
        let run = |seed| {
            let mut es = SepCmaEs::new(vec![0.0; 6], 0.5, 0);
            let mut rng = Rng::new(seed);
            for _ in 0..150 {
                let s = es.ask(&mut rng);
                let c: Vec<f64> = s.iter().map(|s| f(&s.x)).collect();
                es.tell(&s, &c);
            }
            es.mean
        };
        let a = run(7);
        assert!(f(&a) < 1e-8, "{a:?}");
        assert_eq!(a, run(7));
    }
}
