//! The FMI 2.0 C entry points: all 34 common and co-simulation functions. Each one
//! catches panics (a panic must never cross into the host), checks its pointers, and
//! reports refusals through the host's logger with a message that names the problem.

#![allow(non_snake_case, non_camel_case_types)]

use std::ffi::{CStr, CString, c_char, c_int, c_uint, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};

use crate::instance::{FmuError, Instance, ModelContext};
use crate::models;

type fmi2Component = *mut c_void;
type fmi2ComponentEnvironment = *mut c_void;
type fmi2FMUstate = *mut c_void;
type fmi2String = *const c_char;
type fmi2Boolean = c_int;
type fmi2Status = c_int;
type fmi2Type = c_int;
type fmi2ValueReference = c_uint;
type fmi2Real = f64;
type fmi2Integer = c_int;
type fmi2Byte = c_char;
type fmi2StatusKind = c_int;

const FMI2_OK: fmi2Status = 0;
const FMI2_ERROR: fmi2Status = 3;
const FMI2_FATAL: fmi2Status = 4;
const FMI2_CO_SIMULATION: fmi2Type = 1;

type Logger = unsafe extern "C" fn(
    fmi2ComponentEnvironment,
    fmi2String,
    fmi2Status,
    fmi2String,
    fmi2String,
    ...
);

/// The callbacks struct of the FMI 2.0 standard.
#[repr(C)]
pub struct fmi2CallbackFunctions {
    logger: Option<Logger>,
    _allocate_memory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    _free_memory: Option<unsafe extern "C" fn(*mut c_void)>,
    _step_finished: Option<unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2Status)>,
    component_environment: fmi2ComponentEnvironment,
}

/// What fmi2Instantiate hands out: the instance plus what logging needs.
struct Component {
    instance: Instance,
    name: CString,
    logger: Option<Logger>,
    environment: fmi2ComponentEnvironment,
    debug_logging: bool,
}

impl Component {
    fn log(&self, status: fmi2Status, category: &str, message: &str) {
        let Some(logger) = self.logger else { return };
        let category = CString::new(category).unwrap_or_default();
        let message = CString::new(message.replace('\0', " ")).unwrap_or_default();
        // SAFETY: the logger was given by the host in fmi2Instantiate; every pointer is a
        // valid NUL-terminated string that outlives the call, and the format "%s"
        // consumes exactly the one string argument we pass.
        unsafe {
            logger(
                self.environment,
                self.name.as_ptr(),
                status,
                category.as_ptr(),
                c"%s".as_ptr(),
                message.as_ptr(),
            );
        }
    }

    /// Refuse a call whose value array is null although `n > 0`.
    fn null_array(&self, call: &str) -> fmi2Status {
        self.log(
            FMI2_ERROR,
            "logStatusError",
            &format!("{call}: null array with n > 0"),
        );
        FMI2_ERROR
    }

    fn report(&mut self, result: Result<(), FmuError>) -> fmi2Status {
        match result {
            Ok(()) => FMI2_OK,
            Err(e) => {
                let e = self.instance.fail(e);
                self.log(FMI2_ERROR, "logStatusError", &e.to_string());
                FMI2_ERROR
            }
        }
    }
}

/// Run `f` on the component behind `c`, turning a null pointer into fmi2Error and a
/// panic into fmi2Fatal.
fn with_component(c: fmi2Component, f: impl FnOnce(&mut Component) -> fmi2Status) -> fmi2Status {
    if c.is_null() {
        return FMI2_ERROR;
    }
    // SAFETY: a non-null fmi2Component is, by the FMI contract, a pointer this library
    // returned from fmi2Instantiate and that was not yet freed.
    let comp = unsafe { &mut *(c as *mut Component) };
    match catch_unwind(AssertUnwindSafe(|| f(comp))) {
        Ok(status) => status,
        Err(_) => {
            comp.log(
                FMI2_FATAL,
                "logStatusFatal",
                "internal error (panic) in plamo; the instance is unusable",
            );
            FMI2_FATAL
        }
    }
}

/// Borrow `n` elements at `p` (empty when n == 0, whatever p is).
///
/// # Safety
/// When n > 0, p must point to n valid, initialised elements.
unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        return Some(&[]);
    }
    // SAFETY: guaranteed by the caller.
    (!p.is_null()).then(|| unsafe { std::slice::from_raw_parts(p, n) })
}

/// Mutable variant of [`slice`].
///
/// # Safety
/// When n > 0, p must point to n writable elements.
unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        return Some(&mut []);
    }
    // SAFETY: guaranteed by the caller.
    (!p.is_null()).then(|| unsafe { std::slice::from_raw_parts_mut(p, n) })
}

/// # Safety
/// p must be null or a valid NUL-terminated string.
unsafe fn text(p: fmi2String) -> Option<String> {
    // SAFETY: guaranteed by the caller.
    (!p.is_null()).then(|| unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
}

fn resources_dir(location: Option<String>) -> Option<std::path::PathBuf> {
    let loc = location?;
    let path = loc.strip_prefix("file://").unwrap_or(&loc);
    // file:///a/b and file:/a/b both mean /a/b.
    let path = if path.starts_with('/') {
        path.to_string()
    } else {
        format!("/{path}")
    };
    Some(std::path::PathBuf::from(path))
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// # Safety
/// FMI contract: valid strings and callback struct.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Instantiate(
    instance_name: fmi2String,
    fmu_type: fmi2Type,
    guid: fmi2String,
    resource_location: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    logging_on: fmi2Boolean,
) -> fmi2Component {
    let result = catch_unwind(|| {
        // SAFETY: the host passes valid strings or null (checked in `text`).
        let (name, guid, location) =
            unsafe { (text(instance_name), text(guid), text(resource_location)) };
        // SAFETY: `functions` is null or points to the host's callback struct.
        let callbacks = unsafe { functions.as_ref() };
        let mut comp = Component {
            instance: Instance::new(
                models::planner_spec(),
                models::planner_factory,
                ModelContext::default(),
            ),
            name: CString::new(name.clone().unwrap_or_default()).unwrap_or_default(),
            logger: callbacks.and_then(|c| c.logger),
            environment: callbacks.map_or(std::ptr::null_mut(), |c| c.component_environment),
            debug_logging: logging_on != 0,
        };
        let refuse = |comp: &Component, msg: String| {
            comp.log(FMI2_ERROR, "logStatusError", &msg);
            std::ptr::null_mut::<c_void>()
        };
        if name.as_deref().is_none_or(str::is_empty) {
            return refuse(
                &comp,
                "fmi2Instantiate: instanceName must be a non-empty string".into(),
            );
        }
        if fmu_type != FMI2_CO_SIMULATION {
            return refuse(
                &comp,
                format!(
                    "fmi2Instantiate: fmuType {fmu_type} is not supported; plamo FMUs are co-simulation only (fmi2CoSimulation = 1)"
                ),
            );
        }
        let Some((spec, factory)) = guid.as_deref().and_then(models::by_guid) else {
            return refuse(
                &comp,
                format!(
                    "fmi2Instantiate: GUID {:?} does not match this binary; expected one of {:?}",
                    guid,
                    models::guids()
                ),
            );
        };
        comp.instance = Instance::new(
            spec,
            factory,
            ModelContext {
                resources: resources_dir(location),
            },
        );
        Box::into_raw(Box::new(comp)) as fmi2Component
    });
    result.unwrap_or(std::ptr::null_mut())
}

/// # Safety
/// `c` must be an instance from fmi2Instantiate, freed at most once.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    if c.is_null() {
        return;
    }
    // SAFETY: `c` came from Box::into_raw in fmi2Instantiate and is freed once.
    let _ = catch_unwind(|| drop(unsafe { Box::from_raw(c as *mut Component) }));
}

/// # Safety
/// FMI contract.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    on: fmi2Boolean,
    _n: usize,
    _categories: *const fmi2String,
) -> fmi2Status {
    with_component(c, |comp| {
        comp.debug_logging = on != 0;
        FMI2_OK
    })
}

/// # Safety
/// FMI contract.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    _tolerance_defined: fmi2Boolean,
    _tolerance: fmi2Real,
    start_time: fmi2Real,
    _stop_time_defined: fmi2Boolean,
    _stop_time: fmi2Real,
) -> fmi2Status {
    with_component(c, |comp| {
        let r = comp.instance.setup_experiment(start_time);
        comp.report(r)
    })
}

/// # Safety
/// FMI contract.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    with_component(c, |comp| {
        let r = comp.instance.enter_initialization();
        comp.report(r)
    })
}

/// # Safety
/// FMI contract.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    with_component(c, |comp| {
        let r = comp.instance.exit_initialization();
        comp.report(r)
    })
}

/// # Safety
/// FMI contract.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    with_component(c, |comp| {
        let r = comp.instance.terminate();
        comp.report(r)
    })
}

/// # Safety
/// FMI contract.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    with_component(c, |comp| {
        comp.instance.reset();
        FMI2_OK
    })
}

macro_rules! get_values {
    ($fn_name:ident, $ty:ty, $method:ident) => {
        /// # Safety
        /// FMI contract: `vr` and `value` point to `n` elements.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $fn_name(
            c: fmi2Component,
            vr: *const fmi2ValueReference,
            n: usize,
            value: *mut $ty,
        ) -> fmi2Status {
            with_component(c, |comp| {
                // SAFETY: FMI contract: both arrays hold n elements.
                let (Some(vrs), Some(out)) =
                    (unsafe { slice(vr, n) }, unsafe { slice_mut(value, n) })
                else {
                    return comp.null_array(stringify!($fn_name));
                };
                let r = comp.instance.$method(vrs, out);
                comp.report(r)
            })
        }
    };
}

get_values!(fmi2GetReal, fmi2Real, get_real);
get_values!(fmi2GetInteger, fmi2Integer, get_integer);

/// # Safety
/// FMI contract: `vr` and `value` point to `n` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    with_component(c, |comp| {
        // SAFETY: FMI contract: both arrays hold n elements.
        let (Some(vrs), Some(out)) = (unsafe { slice(vr, n) }, unsafe { slice_mut(value, n) })
        else {
            return comp.null_array("fmi2GetBoolean");
        };
        let mut tmp = vec![false; n];
        let r = comp.instance.get_boolean(vrs, &mut tmp);
        for (o, b) in out.iter_mut().zip(&tmp) {
            *o = c_int::from(*b);
        }
        comp.report(r)
    })
}

/// # Safety
/// FMI contract: `vr` and `value` point to `n` elements. Returned strings stay valid
/// until the variable changes or the instance is freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    with_component(c, |comp| {
        // SAFETY: FMI contract: both arrays hold n elements.
        let (Some(vrs), Some(out)) = (unsafe { slice(vr, n) }, unsafe { slice_mut(value, n) })
        else {
            return comp.null_array("fmi2GetString");
        };
        for (r, o) in vrs.iter().zip(out.iter_mut()) {
            match comp.instance.get_string(*r) {
                Ok(s) => *o = s.as_ptr(),
                Err(e) => return comp.report(Err(e)),
            }
        }
        FMI2_OK
    })
}

/// # Safety
/// FMI contract: `vr` and `value` point to `n` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    with_component(c, |comp| {
        // SAFETY: FMI contract: both arrays hold n elements.
        let (Some(vrs), Some(vals)) = (unsafe { slice(vr, n) }, unsafe { slice(value, n) }) else {
            return comp.null_array("fmi2SetReal");
        };
        let r = comp.instance.set_real(vrs, vals);
        comp.report(r)
    })
}

/// # Safety
/// FMI contract: `vr` and `value` point to `n` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    value: *const fmi2Integer,
) -> fmi2Status {
    with_component(c, |comp| {
        // SAFETY: FMI contract: both arrays hold n elements.
        let (Some(vrs), Some(vals)) = (unsafe { slice(vr, n) }, unsafe { slice(value, n) }) else {
            return comp.null_array("fmi2SetInteger");
        };
        let r = comp.instance.set_integer(vrs, vals);
        comp.report(r)
    })
}

/// # Safety
/// FMI contract: `vr` and `value` point to `n` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    with_component(c, |comp| {
        // SAFETY: FMI contract: both arrays hold n elements.
        let (Some(vrs), Some(vals)) = (unsafe { slice(vr, n) }, unsafe { slice(value, n) }) else {
            return comp.null_array("fmi2SetBoolean");
        };
        let vals: Vec<bool> = vals.iter().map(|b| *b != 0).collect();
        let r = comp.instance.set_boolean(vrs, &vals);
        comp.report(r)
    })
}

/// # Safety
/// FMI contract: `vr` and `value` point to `n` elements, each a valid string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    n: usize,
    value: *const fmi2String,
) -> fmi2Status {
    with_component(c, |comp| {
        // SAFETY: FMI contract: both arrays hold n elements.
        let (Some(vrs), Some(vals)) = (unsafe { slice(vr, n) }, unsafe { slice(value, n) }) else {
            return comp.null_array("fmi2SetString");
        };
        for (r, v) in vrs.iter().zip(vals) {
            // SAFETY: each element is null or a valid string (FMI contract).
            let Some(s) = (unsafe { text(*v) }) else {
                comp.log(
                    FMI2_ERROR,
                    "logStatusError",
                    &format!("fmi2SetString: null string for value reference {r}"),
                );
                return FMI2_ERROR;
            };
            let result = comp
                .instance
                .set_string(*r, CString::new(s).unwrap_or_default());
            if result.is_err() {
                return comp.report(result);
            }
        }
        FMI2_OK
    })
}

/// # Safety
/// FMI contract.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DoStep(
    c: fmi2Component,
    current: fmi2Real,
    step: fmi2Real,
    _no_set_prior: fmi2Boolean,
) -> fmi2Status {
    with_component(c, |comp| {
        let r = comp.instance.do_step(current, step);
        comp.report(r)
    })
}

/// Log why an optional FMI function is refused.
fn refuse(c: fmi2Component, call: &str, why: &str) -> fmi2Status {
    with_component(c, |comp| {
        comp.log(
            FMI2_ERROR,
            "logStatusError",
            &format!("{call} is not supported by plamo: {why}"),
        );
        FMI2_ERROR
    })
}

const NO_STATE: &str = "canGetAndSetFMUstate is false in modelDescription.xml";
const NO_DERIVATIVES: &str = "the FMU declares no derivatives (maxOutputDerivativeOrder = 0)";
const SYNC_STEPS: &str = "fmi2DoStep always completes synchronously";

/// Define optional FMI functions that plamo refuses with a logged reason.
macro_rules! unsupported {
    ($($name:ident($($arg:ident: $ty:ty),*) => $why:expr;)*) => {$(
        /// # Safety
        /// FMI contract: `c` is null or a live instance.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $name(c: fmi2Component, $($arg: $ty),*) -> fmi2Status {
            refuse(c, stringify!($name), $why)
        }
    )*};
}

unsupported! {
    fmi2GetFMUstate(_s: *mut fmi2FMUstate) => NO_STATE;
    fmi2SetFMUstate(_s: fmi2FMUstate) => NO_STATE;
    fmi2FreeFMUstate(_s: *mut fmi2FMUstate) => NO_STATE;
    fmi2SerializedFMUstateSize(_s: fmi2FMUstate, _n: *mut usize) => NO_STATE;
    fmi2SerializeFMUstate(_s: fmi2FMUstate, _b: *mut fmi2Byte, _n: usize) => NO_STATE;
    fmi2DeSerializeFMUstate(_b: *const fmi2Byte, _n: usize, _s: *mut fmi2FMUstate) => NO_STATE;
    fmi2GetDirectionalDerivative(_u: *const fmi2ValueReference, _nu: usize, _z: *const fmi2ValueReference, _nz: usize, _dv: *const fmi2Real, _dz: *mut fmi2Real) => NO_DERIVATIVES;
    fmi2SetRealInputDerivatives(_vr: *const fmi2ValueReference, _n: usize, _order: *const fmi2Integer, _value: *const fmi2Real) => NO_DERIVATIVES;
    fmi2GetRealOutputDerivatives(_vr: *const fmi2ValueReference, _n: usize, _order: *const fmi2Integer, _value: *mut fmi2Real) => NO_DERIVATIVES;
    fmi2CancelStep() => SYNC_STEPS;
    fmi2GetStatus(_k: fmi2StatusKind, _v: *mut fmi2Status) => SYNC_STEPS;
    fmi2GetRealStatus(_k: fmi2StatusKind, _v: *mut fmi2Real) => SYNC_STEPS;
    fmi2GetIntegerStatus(_k: fmi2StatusKind, _v: *mut fmi2Integer) => SYNC_STEPS;
    fmi2GetBooleanStatus(_k: fmi2StatusKind, _v: *mut fmi2Boolean) => SYNC_STEPS;
    fmi2GetStringStatus(_k: fmi2StatusKind, _v: *mut fmi2String) => SYNC_STEPS;
}
