//! Quadratic discriminant analysis (the paper's QDA), robust to singular classes.

use crate::classifier::Classifier;
use crate::data::Dataset;
use crate::error::{ForestError, Result};

/// Largest feature count for which prediction uses stack buffers (more features allocate per row).
const STACK_FEATURES: usize = 32;

/// Parameters of [`Qda::fit`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QdaParams {
    /// Regularisation in `[0, 1]`, as scikit-learn's `reg_param`: `Σ_k ← (1 − r)·Σ_k + r·I`, applied in the
    /// standardised space when `standardize` is on (so `r` is relative to each feature's spread).
    pub reg_param: f64,
    /// Standardise the features (pooled mean and standard deviation of the training set) first. With raw
    /// ADC counts (variances in the hundreds), `r·I` is only meaningful in standardised units.
    pub standardize: bool,
}

impl Default for QdaParams {
    /// `reg_param = 1e-3`, standardised.
    fn default() -> Self {
        Self {
            reg_param: 1e-3,
            standardize: true,
        }
    }
}

/// Relative floor on covariance eigenvalues (times the mean feature variance), so a singular class (a
/// constant feature, fewer rows than features) still has a finite density.
const EIGEN_FLOOR: f64 = 1e-6;

#[derive(Debug, Clone, PartialEq)]
struct ClassModel {
    mean: Vec<f64>,
    /// Eigenvectors, row-major `p × p`: column `j` is eigenvector `j`.
    rot: Vec<f64>,
    inv_eig: Vec<f64>,
    /// `−½ Σ log λ + log prior`.
    offset: f64,
}

/// A fitted QDA model: one Gaussian per class with its own covariance, priors = class frequencies.
///
/// The covariance of each class is diagonalised once (Jacobi); eigenvalues are regularised and floored, so
/// the log-densities are always finite for finite input. Probabilities come from a max-shifted softmax of
/// the log-posteriors. A class absent from the training data gets probability 0. A non-finite input gives
/// NaN probabilities (use `try_predict` to reject it).
#[derive(Debug, Clone, PartialEq)]
pub struct Qda {
    n_features: usize,
    n_classes: usize,
    shift: Vec<f64>,
    inv_scale: Vec<f64>,
    classes: Vec<Option<ClassModel>>,
}

impl Qda {
    /// Fits class means and covariances.
    pub fn fit(data: &Dataset, params: QdaParams) -> Result<Self> {
        if !(0.0..=1.0).contains(&params.reg_param) {
            return Err(ForestError::InvalidParams(format!(
                "reg_param {} not in [0, 1]",
                params.reg_param
            )));
        }
        let p = data.n_features();
        let n = data.n_rows();
        let x = data.x();
        let (mut shift, mut inv_scale) = (vec![0f64; p], vec![1f64; p]);
        if params.standardize {
            for f in 0..p {
                let m = (0..n).map(|r| x[r * p + f] as f64).sum::<f64>() / n as f64;
                let var = (0..n)
                    .map(|r| (x[r * p + f] as f64 - m).powi(2))
                    .sum::<f64>()
                    / n as f64;
                shift[f] = m;
                let sd = var.sqrt();
                inv_scale[f] = if sd > 1e-12 * m.abs().max(1.0) {
                    1.0 / sd
                } else {
                    1.0
                };
            }
        }
        let z = |r: usize, f: usize| (x[r * p + f] as f64 - shift[f]) * inv_scale[f];
        // Mean feature variance in the working space sets the scale of the eigenvalue floor.
        let mut mean_var = 0.0;
        for f in 0..p {
            let m = (0..n).map(|r| z(r, f)).sum::<f64>() / n as f64;
            mean_var += (0..n).map(|r| (z(r, f) - m).powi(2)).sum::<f64>() / n as f64;
        }
        mean_var /= p as f64;
        let floor = EIGEN_FLOOR
            * if mean_var > 0.0 && mean_var.is_finite() {
                mean_var
            } else {
                1.0
            };

        let k = data.n_classes();
        let mut rows_of: Vec<Vec<usize>> = vec![Vec::new(); k];
        for (r, &c) in data.y().iter().enumerate() {
            rows_of[c as usize].push(r);
        }
        let r = params.reg_param;
        let classes = rows_of
            .iter()
            .map(|rows| {
                if rows.is_empty() {
                    return None;
                }
                let nk = rows.len();
                let mean: Vec<f64> = (0..p)
                    .map(|f| rows.iter().map(|&i| z(i, f)).sum::<f64>() / nk as f64)
                    .collect();
                let denom = nk.saturating_sub(1).max(1) as f64;
                let mut cov = vec![0f64; p * p];
                for &i in rows {
                    for a in 0..p {
                        let da = z(i, a) - mean[a];
                        for b in 0..=a {
                            cov[a * p + b] += da * (z(i, b) - mean[b]);
                        }
                    }
                }
                for a in 0..p {
                    for b in 0..=a {
                        let v = (1.0 - r) * cov[a * p + b] / denom + if a == b { r } else { 0.0 };
                        cov[a * p + b] = v;
                        cov[b * p + a] = v;
                    }
                }
                let (eig, rot) = sym_eigen(cov, p);
                let eig: Vec<f64> = eig
                    .iter()
                    .map(|&l| if l.is_finite() { l.max(floor) } else { floor })
                    .collect();
                let log_det: f64 = eig.iter().map(|l| l.ln()).sum();
                let prior = nk as f64 / n as f64;
                Some(ClassModel {
                    mean,
                    rot,
                    inv_eig: eig.iter().map(|l| 1.0 / l).collect(),
                    offset: -0.5 * log_det + prior.ln(),
                })
            })
            .collect();
        Ok(Self {
            n_features: p,
            n_classes: k,
            shift,
            inv_scale,
            classes,
        })
    }

    fn log_posteriors(&self, x: &[f32], d: &mut [f64], out: &mut [f32]) {
        let p = self.n_features;
        let mut ll_max = f64::NEG_INFINITY;
        // Two passes (max, then shifted exponentials) keep the log-posteriors in f64 without a buffer.
        for cm in self.classes.iter().flatten() {
            let ll = self.class_ll(cm, x, d, p);
            if ll > ll_max {
                ll_max = ll;
            }
        }
        let mut sum = 0.0;
        for (o, cm) in out.iter_mut().zip(&self.classes) {
            *o = match cm {
                Some(cm) => {
                    let e = (self.class_ll(cm, x, d, p) - ll_max).exp();
                    sum += e;
                    e as f32
                }
                None => 0.0,
            };
        }
        let inv = 1.0 / sum;
        for o in out.iter_mut() {
            *o = (*o as f64 * inv) as f32;
        }
    }

    fn class_ll(&self, cm: &ClassModel, x: &[f32], d: &mut [f64], p: usize) -> f64 {
        for (f, df) in d.iter_mut().enumerate().take(p) {
            let v = x.get(f).map_or(f64::NAN, |&v| v as f64);
            *df = (v - self.shift[f]) * self.inv_scale[f] - cm.mean[f];
        }
        let mut q = 0.0;
        for (j, inv) in cm.inv_eig.iter().enumerate() {
            let proj: f64 = d
                .iter()
                .enumerate()
                .take(p)
                .map(|(f, df)| df * cm.rot[f * p + j])
                .sum();
            q += proj * proj * inv;
        }
        cm.offset - 0.5 * q
    }
}

impl Classifier for Qda {
    fn n_classes(&self) -> usize {
        self.n_classes
    }
    fn n_features(&self) -> usize {
        self.n_features
    }
    fn predict_proba_into(&self, x: &[f32], out: &mut [f32]) {
        let k = self.n_classes.min(out.len());
        if k < self.n_classes {
            let mut buf = vec![0f32; self.n_classes];
            self.predict_proba_into(x, &mut buf);
            out.copy_from_slice(&buf[..k]);
            return;
        }
        let p = self.n_features;
        if p <= STACK_FEATURES {
            let mut d = [0f64; STACK_FEATURES];
            self.log_posteriors(x, &mut d[..p], &mut out[..k]);
        } else {
            let mut d = vec![0f64; p];
            self.log_posteriors(x, &mut d, &mut out[..k]);
        }
    }
}

/// Eigen-decomposition of a symmetric `n × n` matrix (row-major) by cyclic Jacobi rotations. Returns the
/// eigenvalues and the eigenvectors (row-major; column `j` belongs to eigenvalue `j`).
pub(crate) fn sym_eigen(mut a: Vec<f64>, n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut v = vec![0f64; n * n];
    for i in 0..n {
        v[i * n + i] = 1.0;
    }
    let norm: f64 = a.iter().map(|x| x * x).sum::<f64>();
    for _sweep in 0..100 {
        let off: f64 = (0..n)
            .flat_map(|p| (p + 1..n).map(move |q| (p, q)))
            .map(|(p, q)| a[p * n + q].powi(2))
            .sum();
        if off.is_nan() || off <= 1e-30 * norm {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq == 0.0 {
                    continue;
                }
                let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..n {
                    let (akp, akq) = (a[k * n + p], a[k * n + q]);
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                }
                for k in 0..n {
                    let (apk, aqk) = (a[p * n + k], a[q * n + k]);
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
                for k in 0..n {
                    let (vkp, vkq) = (v[k * n + p], v[k * n + q]);
                    v[k * n + p] = c * vkp - s * vkq;
                    v[k * n + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    ((0..n).map(|i| a[i * n + i]).collect(), v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobi_reconstructs() {
        let m = vec![4.0, 1.0, 0.5, 1.0, 3.0, -0.2, 0.5, -0.2, 2.0];
        let (e, v) = sym_eigen(m.clone(), 3);
        for i in 0..3 {
            for j in 0..3 {
                let r: f64 = (0..3).map(|k| v[i * 3 + k] * e[k] * v[j * 3 + k]).sum();
                assert!((r - m[i * 3 + j]).abs() < 1e-10, "{i},{j}: {r}");
            }
        }
        let (e, _) = sym_eigen(vec![0.0; 4], 2);
        assert_eq!(e, vec![0.0, 0.0]);
    }

    #[test]
    fn separates_gaussians() {
        // Class 0 tight around 0, class 1 wide around 0: QDA (not LDA) can separate by spread.
        let mut x = Vec::new();
        let mut y = Vec::new();
        for i in 0..200 {
            let t = i as f32 / 200.0 - 0.5;
            x.extend_from_slice(&[t * 0.2, -t * 0.2]);
            y.push(0);
            x.extend_from_slice(&[t * 20.0, (t * 7.0).sin() * 10.0]);
            y.push(1);
        }
        let d = Dataset::new(x, 2, y).unwrap();
        let m = Qda::fit(&d, QdaParams::default()).unwrap();
        assert_eq!(m.predict(&[0.01, 0.0]), 0);
        assert_eq!(m.predict(&[8.0, -5.0]), 1);
        let p = m.predict_proba(&[0.01, 0.0]);
        assert!((p.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        assert!(m.try_predict(&[f32::NAN, 0.0]).is_err());
        assert!(Qda::fit(
            &d,
            QdaParams {
                reg_param: 1.5,
                standardize: true
            }
        )
        .is_err());
    }
}
