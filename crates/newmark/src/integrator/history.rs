//! The accepted states the extrapolating predictor reads (`newton.rs`,
//! `predict`; `docs/theory.md`, "The predictor").
//!
//! Linear extrapolation of `ü` and `λ` over the last two steps is exact for
//! motion that is linear in time and leaves `h² ẍ` of a smooth `x`. The
//! multipliers and the accelerations of a long chain also alternate from
//! step to step: the scheme's root at `−ρ∞` rings every disturbance the
//! constraints take (a converged step's residual, a fast change of load),
//! and linear extrapolation of an alternation `c (−1)ᵏ` misses by `4 c`. On
//! the planar chain of 10⁵ bars that is 140 N of the top link's 5·10³ N,
//! the error that makes the first correction miss the tolerance
//! (`docs/performance.md`, "The second Newton iteration at 10⁵ bodies").
//!
//! Over five steps of one size the predictor
//! `x_{n+1}⁰ = x_n + 2 x_{n−1} − 2 x_{n−2} − x_{n−3} + x_{n−4}` is exact for
//! `1, k, k², (−1)ᵏ, k (−1)ᵏ`: smooth motion to second order and an
//! alternation whose amplitude drifts linearly. Its weights sum to 7 in
//! magnitude against linear extrapolation's 3, so on motion the steps do not
//! resolve (a pendulum at `h = 0.1` s) it predicts worse. Every
//! [`JUDGE_EVERY`] steps the predictor therefore also measures how far each
//! rule missed the state it starts from, `ü_n` and `λ_n`, and the next steps
//! of `ü` (of `λ`) use the five-step rule only when it missed `ü_n` (`λ_n`)
//! by less in `‖·‖∞`.
//! After a change of step size (step control, a last step cut short to reach
//! the end time) the predictor is linear until five steps of the new size
//! are taken and judged, and so it is after a step whose local error
//! estimate exceeded its tolerance: extrapolating motion the steps do not
//! resolve over five of them sent the pendulum of `models/pendulum.toml` at
//! `h = 0.04` s (ten times its default step) to a spurious root of the step's
//! equations, whose energy grew without bound, where the linear rule does
//! not.

use super::State;
use crate::Predictor;

/// How `ü_{n+1}⁰` and `λ⁰` are formed for one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Rule {
    /// `ü⁰ = 0`, `λ⁰ = λ_n` (the paper's eq. 14a).
    Zero,
    /// `ü⁰ = ü_n`, `λ⁰ = λ_n`.
    Constant,
    /// Linear over the last step, whose size was `h / ratio`.
    Linear { ratio: f64 },
    /// Over the last four steps, all of this step's size.
    FiveStep,
}

impl Rule {
    /// `x_{n+1}⁰` of every entry into `out`, from `x` (`x_n`) and the same
    /// quantity's past values `past` (`x_{n−1}, x_{n−2}, …`, newest first;
    /// only as many as the rule reads need be filled).
    pub(super) fn extrapolate_into(self, x: &[f64], past: Past<'_>, out: &mut [f64]) {
        let [p1, p2, p3, p4, _] = past;
        match self {
            Rule::Zero | Rule::Constant => out.copy_from_slice(x),
            Rule::Linear { ratio } => {
                for ((o, &x0), &x1) in out.iter_mut().zip(x).zip(p1) {
                    *o = x0 + ratio * (x0 - x1);
                }
            }
            Rule::FiveStep => {
                let older = p1.iter().zip(p2).zip(p3).zip(p4);
                for ((o, &x0), (((&x1, &x2), &x3), &x4)) in out.iter_mut().zip(x).zip(older) {
                    *o = five_step(x0, x1, x2, x3, x4);
                }
            }
        }
    }
}

/// `x_{n−1}, …, x_{n−5}` of one quantity, newest first.
pub(super) type Past<'a> = [&'a [f64]; 5];

/// The five-step rule's `x_{n+1}⁰` from `x_n, …, x_{n−4}`.
#[inline(always)]
pub(super) fn five_step(x0: f64, x1: f64, x2: f64, x3: f64, x4: f64) -> f64 {
    x0 + 2.0 * x1 - 2.0 * x2 - x3 + x4
}

/// How far the five-step and the linear rule (equal steps) missed `x_n`
/// from the states before it, in `‖·‖∞`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Misses {
    five_step: f64,
    linear: f64,
}

impl Misses {
    /// Of `x_n` (`x`) from `x_{n−1}, …, x_{n−5}` (`past`).
    pub(super) fn of(x: &[f64], past: Past<'_>) -> Self {
        let [p1, p2, p3, p4, p5] = past;
        let older = p1.iter().zip(p2).zip(p3).zip(p4).zip(p5);
        let (mut five, mut linear) = (0.0f64, 0.0f64);
        for (&x0, ((((&x1, &x2), &x3), &x4), &x5)) in x.iter().zip(older) {
            five = five.max((five_step(x1, x2, x3, x4, x5) - x0).abs());
            linear = linear.max((2.0 * x1 - x2 - x0).abs());
        }
        Self {
            five_step: five,
            linear,
        }
    }
}

/// `ü` and `λ` of one accepted state.
#[derive(Clone, Debug, Default)]
struct Older {
    a: Vec<f64>,
    lambda: Vec<f64>,
}

/// The states before the current one, newest first.
#[derive(Clone, Debug, Default)]
pub(super) struct History {
    /// The state before the last accepted step, whole: its buffers rotate
    /// through `trial` (`Integrator::accept`).
    previous: State,
    /// `ü` and `λ` of the four accepted states before `previous` (empty
    /// unless the predictor extrapolates over five steps: `keeps_older`).
    older: [Older; 4],
    keeps_older: bool,
    /// The sizes of the last five accepted steps, newest first.
    steps: [Option<f64>; 5],
    /// Whether each of those steps' local error estimate was within its
    /// tolerance.
    resolved: [bool; 5],
    /// Whether the next step of `ü` and of `λ` takes the five-step rule: it
    /// missed the last judged state by less than the linear rule.
    five_step: [bool; 2],
    /// Accepted steps pushed (judgements are made every [`JUDGE_EVERY`]).
    pushed: u64,
}

/// Steps from one judgement of the rules to the next: a judgement reads six
/// past values of every `ü` and `λ`, a pass that costs about as much as the
/// prediction itself.
const JUDGE_EVERY: u64 = 4;

impl History {
    /// Empty, for `n` coordinates and `m` constraints; `older` is allocated
    /// for [`Predictor::Extrapolated`] only.
    pub(super) fn new(n: usize, m: usize, predictor: Predictor) -> Self {
        let extrapolates = predictor == Predictor::Extrapolated;
        let older = || Older {
            a: vec![0.0; if extrapolates { n } else { 0 }],
            lambda: vec![0.0; if extrapolates { m } else { 0 }],
        };
        Self {
            previous: State::zeros(n, m),
            older: [older(), older(), older(), older()],
            keeps_older: extrapolates,
            steps: [None; 5],
            resolved: [false; 5],
            five_step: [false; 2],
            pushed: 0,
        }
    }

    /// Takes the last accepted `state`, reached by a step of size `h` that
    /// was `resolved` (its local error estimate within the tolerance), as the
    /// newest past state; `state` gets the buffers of the oldest (to be
    /// overwritten).
    pub(super) fn push(&mut self, state: &mut State, h: f64, resolved: bool) {
        if self.keeps_older {
            self.older.rotate_right(1);
            std::mem::swap(&mut self.older[0].a, &mut self.previous.a);
            std::mem::swap(&mut self.older[0].lambda, &mut self.previous.lambda);
        }
        std::mem::swap(&mut self.previous, state);
        self.steps.rotate_right(1);
        self.steps[0] = Some(h);
        self.resolved.rotate_right(1);
        self.resolved[0] = resolved;
        self.pushed += 1;
    }

    /// The rules for `ü` and for `λ` of a step of size `h` with `predictor`.
    pub(super) fn rules(&self, predictor: Predictor, h: f64) -> [Rule; 2] {
        let linear = |last: f64| Rule::Linear { ratio: h / last };
        match (predictor, self.steps[0]) {
            (Predictor::ZeroAcceleration, _) => [Rule::Zero, Rule::Constant],
            (Predictor::ConstantAcceleration, _) | (_, None) => [Rule::Constant; 2],
            (Predictor::Linear, Some(last)) => [linear(last); 2],
            (Predictor::Extrapolated, Some(last)) => {
                let eligible = self.eligible(predictor, h);
                self.five_step.map(|five| {
                    if five && eligible {
                        Rule::FiveStep
                    } else {
                        linear(last)
                    }
                })
            }
        }
    }

    /// Whether a step of size `h` may take the five-step rule and judge it:
    /// the five steps before it had its size and were resolved.
    pub(super) fn eligible(&self, predictor: Predictor, h: f64) -> bool {
        predictor == Predictor::Extrapolated
            && self.steps.iter().all(|&s| s == Some(h))
            && self.resolved.iter().all(|&r| r)
    }

    /// Whether the step of size `h` judges the rules on the last state:
    /// eligible, and every [`JUDGE_EVERY`] steps.
    pub(super) fn judging(&self, predictor: Predictor, h: f64) -> bool {
        self.eligible(predictor, h) && self.pushed.is_multiple_of(JUDGE_EVERY)
    }

    /// Takes the `misses` of `ü` and `λ` when the step judged: the next
    /// steps take the rule that missed by less. Without, the choice stands
    /// while the step is `eligible` and is the linear rule when not.
    pub(super) fn judge(&mut self, misses: Option<[Misses; 2]>, eligible: bool) {
        match misses {
            Some(misses) => self.five_step = misses.map(|m| m.five_step < m.linear),
            None if !eligible => self.five_step = [false; 2],
            None => {}
        }
    }

    /// The past accelerations `ü_{n−1}, …, ü_{n−5}`.
    pub(super) fn a(&self) -> Past<'_> {
        let [o1, o2, o3, o4] = &self.older;
        [&self.previous.a, &o1.a, &o2.a, &o3.a, &o4.a]
    }

    /// The past multipliers `λ_{n−1}, …, λ_{n−5}`.
    pub(super) fn lambda(&self) -> Past<'_> {
        let [o1, o2, o3, o4] = &self.older;
        [
            &self.previous.lambda,
            &o1.lambda,
            &o2.lambda,
            &o3.lambda,
            &o4.lambda,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `f(0), f(−1), …, f(−5)`.
    fn samples(f: impl Fn(f64) -> f64) -> [[f64; 1]; 6] {
        [0.0, -1.0, -2.0, -3.0, -4.0, -5.0].map(|k| [f(k)])
    }

    /// The rule's prediction of `f(1)` from `f(0), f(−1), …`.
    fn predicted(rule: Rule, f: impl Fn(f64) -> f64) -> f64 {
        let [x, p1, p2, p3, p4, p5] = samples(f);
        let mut out = [0.0];
        rule.extrapolate_into(&x, [&p1, &p2, &p3, &p4, &p5], &mut out);
        out[0]
    }

    fn alternating(k: f64) -> f64 {
        if k.rem_euclid(2.0) == 0.0 { 1.0 } else { -1.0 }
    }

    #[test]
    fn five_steps_are_exact_for_quadratics_and_a_drifting_alternation() {
        type Case = (&'static str, fn(f64) -> f64);
        let cases: [Case; 5] = [
            ("1", |_| 1.0),
            ("k", |k| k),
            ("k²", |k| k * k),
            ("(−1)ᵏ", alternating),
            ("k (−1)ᵏ", |k| k * alternating(k)),
        ];
        for (name, f) in cases {
            let p = predicted(Rule::FiveStep, f);
            assert!((p - f(1.0)).abs() < 1e-14, "{name}: {p} against {}", f(1.0));
        }
        // Linear extrapolation misses an alternation by four times its
        // amplitude, and k² by 2 (the reason for the five-step rule).
        let linear = Rule::Linear { ratio: 1.0 };
        assert_eq!(predicted(linear, alternating), 3.0);
        assert_eq!(predicted(linear, |k| k * k), -1.0);
        // Its error on k³ (second-order rule: a third derivative's term).
        assert_eq!(predicted(Rule::FiveStep, |k| k * k * k), -23.0);
    }

    #[test]
    fn misses_are_those_of_each_rule_on_the_newest_state() {
        let misses = |f: fn(f64) -> f64| {
            let [x, p1, p2, p3, p4, p5] = samples(f);
            Misses::of(&x, [&p1, &p2, &p3, &p4, &p5])
        };
        // f(0) from f(−1), …: the alternation is the five-step rule's, a
        // cubic is the linear rule's better case.
        let ringing = misses(|k| k + 3.0 * alternating(k));
        assert_eq!((ringing.five_step, ringing.linear), (0.0, 12.0));
        let cubic = misses(|k| k * k * k);
        assert_eq!((cubic.five_step, cubic.linear), (24.0, 6.0));
    }

    /// Pushes `x_k = f(k)` for `k = 1..=count` (as both `ü` and `λ`).
    fn pushed(history: &mut History, f: fn(f64) -> f64, count: u32, h: f64) {
        for k in 1..=count {
            let mut state = State::zeros(1, 1);
            state.a[0] = f(f64::from(k));
            state.lambda[0] = f(f64::from(k));
            history.push(&mut state, h, true);
        }
    }

    #[test]
    fn the_five_step_rule_waits_for_five_equal_steps_and_a_better_miss() {
        let predictor = Predictor::Extrapolated;
        let mut history = History::new(1, 1, predictor);
        assert_eq!(history.rules(predictor, 0.1), [Rule::Constant; 2]);
        pushed(&mut history, |_| 0.0, 1, 0.2);
        let half = Rule::Linear { ratio: 0.5 };
        assert_eq!(history.rules(predictor, 0.1), [half; 2]);
        // Even judged better, the rule needs five steps of this size.
        let better = Misses {
            five_step: 0.5,
            linear: 1.0,
        };
        history.judge(Some([better; 2]), true);
        let linear = Rule::Linear { ratio: 1.0 };
        for _ in 0..4 {
            pushed(&mut history, |_| 0.0, 1, 0.1);
            assert!(!history.eligible(predictor, 0.1));
            assert_eq!(history.rules(predictor, 0.1), [linear; 2]);
        }
        pushed(&mut history, |_| 0.0, 1, 0.1);
        assert!(history.eligible(predictor, 0.1));
        assert_eq!(history.rules(predictor, 0.1), [Rule::FiveStep; 2]);
        assert_eq!(history.rules(predictor, 0.05), [half; 2]);
        // One judgement in every JUDGE_EVERY steps.
        let judged = (0..JUDGE_EVERY)
            .filter(|_| {
                pushed(&mut history, |_| 0.0, 1, 0.1);
                history.judging(predictor, 0.1)
            })
            .count();
        assert_eq!(judged, 1);
        // Each quantity by its own misses; the choice stands between
        // judgements, and is linear when the step is not eligible.
        let worse = Misses {
            five_step: 2.0,
            linear: 1.0,
        };
        history.judge(Some([worse, better]), true);
        assert_eq!(history.rules(predictor, 0.1), [linear, Rule::FiveStep]);
        history.judge(None, true);
        assert_eq!(history.rules(predictor, 0.1), [linear, Rule::FiveStep]);
        history.judge(None, false);
        assert_eq!(history.rules(predictor, 0.1), [linear; 2]);
        // A step beyond its error tolerance stops the rule for five steps.
        let mut state = State::zeros(1, 1);
        history.push(&mut state, 0.1, false);
        for _ in 0..5 {
            assert!(!history.eligible(predictor, 0.1));
            pushed(&mut history, |_| 0.0, 1, 0.1);
        }
        assert!(history.eligible(predictor, 0.1));
        assert_eq!(history.rules(Predictor::Linear, 0.1), [linear; 2]);
        assert_eq!(
            history.rules(Predictor::ZeroAcceleration, 0.1),
            [Rule::Zero, Rule::Constant]
        );
    }

    #[test]
    fn pushed_states_come_back_newest_first() {
        let mut history = History::new(1, 1, Predictor::Extrapolated);
        pushed(&mut history, |k| k, 7, 0.1);
        let a: Vec<f64> = history.a().iter().map(|x| x[0]).collect();
        let lambda: Vec<f64> = history.lambda().iter().map(|x| x[0]).collect();
        assert_eq!(a, [7.0, 6.0, 5.0, 4.0, 3.0]);
        assert_eq!(lambda, a);
    }
}
