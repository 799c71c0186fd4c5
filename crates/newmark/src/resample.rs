//! Output at requested times, whatever steps the integrator took.

use mstar_model::{Sample, SampleRef};

use crate::Observer;

/// An [`Observer`] that hands `inner` the state at `t₀, t₀ + Δt, t₀ + 2Δt, …`
/// instead of at the accepted steps, interpolating within each step:
/// cubic Hermite on `u` from `u, u̇` at both ends and on `u̇` from `u̇, ü`
/// (both exact for cubics, error `O(h⁴)` within a step, below the
/// method's `O(h²)`); `ü`, `λ` and the energies linearly. Iterations, residual
/// and constraint norms are those of the step that contains the time.
///
/// Call [`finish`](Self::finish) at the end of a run (also a failed one) so
/// that the last state reached is handed on when it is not on the grid.
///
/// ```
/// use mstar_model::PendulumChain;
/// use mstar_newmark::{Config, Integrator, Resample, Trajectory};
///
/// let sys = PendulumChain::paper(1.0, 1.0, 9.81);
/// let u0 = sys.position(&[1.0]);
/// let mut integ = Integrator::new(&sys, Config { h: 0.003, ..Config::default() }, 0.0, &u0, &[0.0; 3])?;
/// let mut out = Resample::new(0.1, Trajectory::default());
/// integ.run(0.25, &mut out)?;
/// let traj = out.finish();
/// let times: Vec<f64> = traj.samples.iter().map(|s| s.t).collect();
/// assert_eq!(times.len(), 4); // 0, 0.1, 0.2 and the end, 0.25
/// assert!((times[1] - 0.1).abs() < 1e-15 && (times[3] - 0.25).abs() < 1e-12);
/// # Ok::<(), mstar_newmark::IntegrationError>(())
/// ```
#[derive(Debug)]
pub struct Resample<O: Observer> {
    inner: O,
    dt: f64,
    /// `t₀` and the index of the next grid time `t₀ + k Δt`.
    t0: Option<f64>,
    k: u64,
    /// The last observed state (the left end of the next step).
    last: Sample,
    /// Whether `last` was handed on as it is.
    last_emitted: bool,
    /// The interpolated state handed on.
    out: Sample,
}

/// Copies `s` into `out`, reusing its buffers.
fn copy_from(out: &mut Sample, s: &SampleRef<'_>) {
    out.t = s.t;
    for (dst, src) in [
        (&mut out.u, s.u),
        (&mut out.v, s.v),
        (&mut out.a, s.a),
        (&mut out.lambda, s.lambda),
    ] {
        dst.clear();
        dst.extend_from_slice(src);
    }
    (out.kinetic, out.potential) = (s.kinetic, s.potential);
    (out.iterations, out.residual, out.constraint) = (s.iterations, s.residual, s.constraint);
}

/// The state at `t` in `[l.t, r.t]` into `out`, by the rules of [`Resample`].
fn interpolate(out: &mut Sample, l: &Sample, r: &SampleRef<'_>, t: f64) {
    let h = r.t - l.t;
    let x = ((t - l.t) / h).clamp(0.0, 1.0);
    // Cubic Hermite basis on [0, 1].
    let (x2, x3) = (x * x, x * x * x);
    let h00 = 2.0 * x3 - 3.0 * x2 + 1.0;
    let h10 = x3 - 2.0 * x2 + x;
    let h01 = -2.0 * x3 + 3.0 * x2;
    let h11 = x3 - x2;
    let hermite =
        |p0: f64, d0: f64, p1: f64, d1: f64| h00 * p0 + h10 * h * d0 + h01 * p1 + h11 * h * d1;
    let linear = |p0: f64, p1: f64| p0 + x * (p1 - p0);
    out.t = t;
    for i in 0..l.u.len() {
        out.u[i] = hermite(l.u[i], l.v[i], r.u[i], r.v[i]);
        out.v[i] = hermite(l.v[i], l.a[i], r.v[i], r.a[i]);
        out.a[i] = linear(l.a[i], r.a[i]);
    }
    for (i, x) in out.lambda.iter_mut().enumerate() {
        *x = linear(l.lambda[i], r.lambda[i]);
    }
    out.kinetic = linear(l.kinetic, r.kinetic);
    out.potential = linear(l.potential, r.potential);
    (out.iterations, out.residual, out.constraint) = (r.iterations, r.residual, r.constraint);
}

impl<O: Observer> Resample<O> {
    /// Hands `inner` the state every `dt` seconds from the first observed
    /// time on. `dt` must be positive and finite (the caller checks it).
    pub fn new(dt: f64, inner: O) -> Self {
        Self {
            inner,
            dt,
            t0: None,
            k: 0,
            last: Sample::default(),
            last_emitted: false,
            out: Sample::default(),
        }
    }

    /// Hands on the last state reached if it is not on the grid, and returns
    /// the inner observer.
    pub fn finish(mut self) -> O {
        if self.t0.is_some() && !self.last_emitted {
            self.inner.observe(&self.last.view());
        }
        self.inner
    }

    /// The inner observer.
    pub fn inner(&self) -> &O {
        &self.inner
    }

    /// The inner observer, mutably (to drain what it collected).
    pub fn inner_mut(&mut self) -> &mut O {
        &mut self.inner
    }

    /// `t₀ + k Δt`, as `t₀ + k / n` when `Δt = 1/n` for a whole `n` (so that
    /// 0.1 s steps give 0.3, not 0.30000000000000004).
    fn grid_time(&self, t0: f64) -> f64 {
        let per_second = 1.0 / self.dt;
        let n = per_second.round();
        if n >= 1.0 && (per_second - n).abs() <= 1e-9 * n {
            t0 + self.k as f64 / n
        } else {
            t0 + self.k as f64 * self.dt
        }
    }
}

impl<O: Observer> Observer for Resample<O> {
    fn observe(&mut self, s: &SampleRef<'_>) {
        let Some(t0) = self.t0 else {
            // The initial state is the first grid time.
            self.t0 = Some(s.t);
            self.inner.observe(s);
            self.k = 1;
            copy_from(&mut self.last, s);
            copy_from(&mut self.out, s);
            self.last_emitted = true;
            return;
        };
        // Grid times within round-off of the step's end are the end itself.
        let eps = 1e-9 * self.dt;
        self.last_emitted = false;
        while self.grid_time(t0) <= s.t + eps {
            let t = self.grid_time(t0);
            if (t - s.t).abs() <= eps {
                // The step's own state, at the grid's time to the digit.
                self.inner.observe(&SampleRef { t, ..*s });
                self.last_emitted = true;
            } else {
                interpolate(&mut self.out, &self.last, s, t);
                self.inner.observe(&self.out.view());
            }
            self.k += 1;
        }
        copy_from(&mut self.last, s);
    }

    fn reads_energy(&self) -> bool {
        self.inner.reads_energy()
    }
}
