//! What the adjoint tests share: a model at one set of parameter values, a
//! parameter that remakes it, and a state column read by hand.

use mstar_model::System;
use mstar_newmark::{Column, Parameterized, Variant};

/// A model at one set of parameter values: its system and initial state.
pub struct Model {
    pub sys: Box<dyn System>,
    pub u0: Vec<f64>,
    pub v0: Vec<f64>,
}

impl Variant for Model {
    fn system(&self) -> &dyn System {
        self.sys.as_ref()
    }
    fn initial_position(&self) -> &[f64] {
        &self.u0
    }
    fn initial_velocity(&self) -> &[f64] {
        &self.v0
    }
}

/// Parameter `k` of `nominal`, the model remade by `make` at any value.
pub struct Param {
    pub make: fn(&[f64]) -> Model,
    pub nominal: Vec<f64>,
    pub k: usize,
}

impl Parameterized for Param {
    fn name(&self) -> String {
        format!("p{}", self.k)
    }
    fn value(&self) -> f64 {
        self.nominal[self.k]
    }
    fn at(&self, value: f64) -> Result<Box<dyn Variant>, String> {
        let mut p = self.nominal.clone();
        p[self.k] = value;
        Ok(Box::new((self.make)(&p)))
    }
}

/// The value of column `c` in a state.
// (Not every test file that shares this module reads columns.)
#[allow(dead_code)]
pub fn column_of(u: &[f64], v: &[f64], a: &[f64], lambda: &[f64], c: Column) -> f64 {
    match c {
        Column::Position(i) => u[i],
        Column::Velocity(i) => v[i],
        Column::Acceleration(i) => a[i],
        Column::Multiplier(i) => lambda[i],
    }
}
