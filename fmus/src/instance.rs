//! One FMU instance: the FMI 2.0 co-simulation state machine, the variable values,
//! and the model behind them. Safe Rust; the C boundary is in `ffi.rs`.

use std::ffi::CString;

use crate::spec::{Causality, ModelSpec, VarType};

/// A variable's current value.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// fmi2Real.
    Real(f64),
    /// fmi2Integer.
    Integer(i32),
    /// fmi2Boolean.
    Boolean(bool),
    /// fmi2String; owned by the instance so pointers handed to the host stay valid
    /// until the next call that changes it.
    String(CString),
}

impl Value {
    fn start(ty: VarType, start: Option<&str>) -> Value {
        let s = start.unwrap_or("");
        match ty {
            VarType::Real => Value::Real(s.parse().unwrap_or(0.0)),
            VarType::Integer => Value::Integer(s.parse().unwrap_or(0)),
            VarType::Boolean => Value::Boolean(s == "true"),
            VarType::String => Value::String(CString::new(s).unwrap_or_default()),
        }
    }
}

/// The simulation behind an FMU. Reads parameters and inputs from `values`, writes
/// outputs into it.
/// Not `Send`: an instance lives on whichever thread the host calls it from, one call
/// at a time (FMI 2.0 does not move instances between concurrent threads).
pub trait Model {
    /// Advance the internal simulation to `t` seconds after the start time (it steps
    /// in its own fixed ticks; a `t` between ticks advances to the last tick at or
    /// before it) and write the outputs.
    fn advance(&mut self, t: f64, values: &mut [Value]) -> Result<(), String>;
}

/// What a model may need from its surroundings when it is built.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ModelContext {
    /// The unpacked FMU's `resources/` folder, when the host gave one (scene files can
    /// be shipped there and named by a relative path).
    pub resources: Option<std::path::PathBuf>,
}

/// Builds a model from the parameter values at the end of initialisation.
pub type ModelFactory = fn(&ModelSpec, &ModelContext, &[Value]) -> Result<Box<dyn Model>, String>;

/// FMI 2.0 co-simulation states.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum State {
    /// After fmi2Instantiate or fmi2Reset.
    Instantiated,
    /// Between fmi2EnterInitializationMode and fmi2ExitInitializationMode.
    Initialization,
    /// Ready for fmi2DoStep.
    StepComplete,
    /// After fmi2Terminate.
    Terminated,
    /// After an error; only fmi2Reset and fmi2FreeInstance help.
    Error,
}

/// Why a call was refused. Every message names the problem and what is allowed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FmuError {
    /// The call is not allowed in the current state.
    #[error("{call} is not allowed in state {state:?}; allowed in: {allowed}")]
    WrongState {
        /// The FMI function.
        call: &'static str,
        /// The current state.
        state: State,
        /// The states it is allowed in.
        allowed: &'static str,
    },
    /// No variable has this value reference.
    #[error("unknown value reference {vr}: this FMU has value references 0..{count}")]
    UnknownValueReference {
        /// The value reference.
        vr: u32,
        /// Number of variables.
        count: usize,
    },
    /// The variable has another type than the call.
    #[error("variable `{name}` (value reference {vr}) is {actual:?}, not {requested:?}")]
    WrongType {
        /// The value reference.
        vr: u32,
        /// The variable's name.
        name: String,
        /// Its type.
        actual: VarType,
        /// The type of the call.
        requested: VarType,
    },
    /// The variable cannot be set now.
    #[error("variable `{name}` ({causality:?}) cannot be set in state {state:?}: {rule}")]
    NotSettable {
        /// The variable's name.
        name: String,
        /// Its causality.
        causality: Causality,
        /// The current state.
        state: State,
        /// What is allowed.
        rule: &'static str,
    },
    /// A Real input or parameter was NaN or infinite.
    #[error("variable `{name}` was set to {value}: finite numbers only")]
    NotFinite {
        /// The variable's name.
        name: String,
        /// The value.
        value: f64,
    },
    /// The host's time does not continue where the FMU stands.
    #[error(
        "fmi2DoStep at t = {requested} but the FMU is at t = {current}; steps must be contiguous and > 0 (step size {step})"
    )]
    BadStep {
        /// The host's current communication point.
        requested: f64,
        /// The FMU's time.
        current: f64,
        /// The step size.
        step: f64,
    },
    /// The model failed (bad scene, unreachable goal, physics diverged, ...).
    #[error("{0}")]
    Model(String),
}

/// Relative tolerance on communication points: hosts send 0.009999999999999998.
const TIME_TOLERANCE: f64 = 1e-9;

/// An FMU instance.
pub struct Instance {
    spec: &'static ModelSpec,
    factory: ModelFactory,
    state: State,
    values: Vec<Value>,
    model: Option<Box<dyn Model>>,
    context: ModelContext,
    start_time: f64,
    time: f64,
}

impl Instance {
    /// A fresh instance with every variable at its start value.
    pub fn new(spec: &'static ModelSpec, factory: ModelFactory, context: ModelContext) -> Self {
        let values = spec
            .variables
            .iter()
            .map(|v| Value::start(v.ty, v.start.as_deref()))
            .collect();
        Self {
            spec,
            factory,
            state: State::Instantiated,
            values,
            model: None,
            context,
            start_time: 0.0,
            time: 0.0,
        }
    }

    /// The model's description.
    pub fn spec(&self) -> &'static ModelSpec {
        self.spec
    }

    /// Current state.
    pub fn state(&self) -> State {
        self.state
    }

    /// Current communication time \[s\].
    pub fn time(&self) -> f64 {
        self.time
    }

    fn expect(
        &self,
        call: &'static str,
        allowed: &[State],
        text: &'static str,
    ) -> Result<(), FmuError> {
        if allowed.contains(&self.state) {
            Ok(())
        } else {
            Err(FmuError::WrongState {
                call,
                state: self.state,
                allowed: text,
            })
        }
    }

    /// Remember a failure: the instance goes to the error state.
    pub fn fail(&mut self, e: FmuError) -> FmuError {
        if matches!(e, FmuError::Model(_)) {
            self.state = State::Error;
        }
        e
    }

    /// fmi2SetupExperiment.
    pub fn setup_experiment(&mut self, start_time: f64) -> Result<(), FmuError> {
        self.expect(
            "fmi2SetupExperiment",
            &[State::Instantiated],
            "Instantiated",
        )?;
        if !start_time.is_finite() {
            return Err(FmuError::NotFinite {
                name: "startTime".into(),
                value: start_time,
            });
        }
        self.start_time = start_time;
        self.time = start_time;
        Ok(())
    }

    /// fmi2EnterInitializationMode.
    pub fn enter_initialization(&mut self) -> Result<(), FmuError> {
        self.expect(
            "fmi2EnterInitializationMode",
            &[State::Instantiated],
            "Instantiated",
        )?;
        self.state = State::Initialization;
        Ok(())
    }

    /// fmi2ExitInitializationMode: builds the model from the parameters and computes
    /// the outputs at the start time.
    pub fn exit_initialization(&mut self) -> Result<(), FmuError> {
        self.expect(
            "fmi2ExitInitializationMode",
            &[State::Initialization],
            "Initialization",
        )?;
        let mut model = (self.factory)(self.spec, &self.context, &self.values)
            .map_err(|e| self.fail(FmuError::Model(e)))?;
        model
            .advance(0.0, &mut self.values)
            .map_err(|e| self.fail(FmuError::Model(e)))?;
        self.model = Some(model);
        self.state = State::StepComplete;
        Ok(())
    }

    /// fmi2DoStep.
    pub fn do_step(&mut self, current: f64, step: f64) -> Result<(), FmuError> {
        self.expect(
            "fmi2DoStep",
            &[State::StepComplete],
            "StepComplete (after fmi2ExitInitializationMode)",
        )?;
        let tol = TIME_TOLERANCE * self.time.abs().max(1.0);
        if !step.is_finite() || step <= 0.0 || (current - self.time).abs() > tol {
            return Err(FmuError::BadStep {
                requested: current,
                current: self.time,
                step,
            });
        }
        let target = current + step;
        let model = self.model.as_mut().expect("StepComplete implies a model");
        if let Err(e) = model.advance(target - self.start_time + tol, &mut self.values) {
            return Err(self.fail(FmuError::Model(e)));
        }
        self.time = target;
        Ok(())
    }

    /// fmi2Terminate.
    pub fn terminate(&mut self) -> Result<(), FmuError> {
        self.expect("fmi2Terminate", &[State::StepComplete], "StepComplete")?;
        self.state = State::Terminated;
        Ok(())
    }

    /// fmi2Reset: back to Instantiated with start values.
    pub fn reset(&mut self) {
        *self = Self::new(self.spec, self.factory, self.context.clone());
    }

    fn variable(&self, vr: u32, ty: VarType) -> Result<usize, FmuError> {
        let i = vr as usize;
        let v = self
            .spec
            .variables
            .get(i)
            .ok_or(FmuError::UnknownValueReference {
                vr,
                count: self.spec.variables.len(),
            })?;
        if v.ty != ty {
            return Err(FmuError::WrongType {
                vr,
                name: v.name.clone(),
                actual: v.ty,
                requested: ty,
            });
        }
        Ok(i)
    }

    fn check_get(&self, call: &'static str) -> Result<(), FmuError> {
        self.expect(
            call,
            &[
                State::Instantiated,
                State::Initialization,
                State::StepComplete,
                State::Terminated,
                State::Error,
            ],
            "any state",
        )
    }

    fn settable(&self, i: usize, vr: u32) -> Result<(), FmuError> {
        let v = &self.spec.variables[i];
        let ok = match v.causality {
            Causality::Parameter => {
                matches!(self.state, State::Instantiated | State::Initialization)
            }
            Causality::Input => matches!(
                self.state,
                State::Instantiated | State::Initialization | State::StepComplete
            ),
            Causality::Output => false,
        };
        if ok {
            return Ok(());
        }
        let _ = vr;
        Err(FmuError::NotSettable {
            name: v.name.clone(),
            causality: v.causality,
            state: self.state,
            rule: match v.causality {
                Causality::Parameter => "parameters are fixed after initialisation",
                Causality::Input => "inputs can be set before initialisation and between steps",
                Causality::Output => "outputs are computed by the FMU",
            },
        })
    }

    /// Get Real values.
    pub fn get_real(&self, vrs: &[u32], out: &mut [f64]) -> Result<(), FmuError> {
        self.check_get("fmi2GetReal")?;
        for (vr, o) in vrs.iter().zip(out.iter_mut()) {
            if let Value::Real(x) = self.values[self.variable(*vr, VarType::Real)?] {
                *o = x;
            }
        }
        Ok(())
    }

    /// Get Integer values.
    pub fn get_integer(&self, vrs: &[u32], out: &mut [i32]) -> Result<(), FmuError> {
        self.check_get("fmi2GetInteger")?;
        for (vr, o) in vrs.iter().zip(out.iter_mut()) {
            if let Value::Integer(x) = self.values[self.variable(*vr, VarType::Integer)?] {
                *o = x;
            }
        }
        Ok(())
    }

    /// Get Boolean values.
    pub fn get_boolean(&self, vrs: &[u32], out: &mut [bool]) -> Result<(), FmuError> {
        self.check_get("fmi2GetBoolean")?;
        for (vr, o) in vrs.iter().zip(out.iter_mut()) {
            if let Value::Boolean(x) = self.values[self.variable(*vr, VarType::Boolean)?] {
                *o = x;
            }
        }
        Ok(())
    }

    /// Get a String value; the reference stays valid until the variable changes.
    pub fn get_string(&self, vr: u32) -> Result<&CString, FmuError> {
        self.check_get("fmi2GetString")?;
        match &self.values[self.variable(vr, VarType::String)?] {
            Value::String(s) => Ok(s),
            _ => unreachable!("type checked by variable()"),
        }
    }

    /// Set Real values (all checked before any is written).
    pub fn set_real(&mut self, vrs: &[u32], vals: &[f64]) -> Result<(), FmuError> {
        for (vr, x) in vrs.iter().zip(vals) {
            let i = self.variable(*vr, VarType::Real)?;
            self.settable(i, *vr)?;
            if !x.is_finite() {
                return Err(FmuError::NotFinite {
                    name: self.spec.variables[i].name.clone(),
                    value: *x,
                });
            }
        }
        for (vr, x) in vrs.iter().zip(vals) {
            self.values[*vr as usize] = Value::Real(*x);
        }
        Ok(())
    }

    /// Set Integer values.
    pub fn set_integer(&mut self, vrs: &[u32], vals: &[i32]) -> Result<(), FmuError> {
        for vr in vrs {
            let i = self.variable(*vr, VarType::Integer)?;
            self.settable(i, *vr)?;
        }
        for (vr, x) in vrs.iter().zip(vals) {
            self.values[*vr as usize] = Value::Integer(*x);
        }
        Ok(())
    }

    /// Set Boolean values.
    pub fn set_boolean(&mut self, vrs: &[u32], vals: &[bool]) -> Result<(), FmuError> {
        for vr in vrs {
            let i = self.variable(*vr, VarType::Boolean)?;
            self.settable(i, *vr)?;
        }
        for (vr, x) in vrs.iter().zip(vals) {
            self.values[*vr as usize] = Value::Boolean(*x);
        }
        Ok(())
    }

    /// Set one String value.
    pub fn set_string(&mut self, vr: u32, value: CString) -> Result<(), FmuError> {
        let i = self.variable(vr, VarType::String)?;
        self.settable(i, vr)?;
        self.values[i] = Value::String(value);
        Ok(())
    }
}
