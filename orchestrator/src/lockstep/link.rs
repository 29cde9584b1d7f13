//! How the lockstep reaches a component: directly in this process, or through an
//! iceoryx2 [`RemoteComponent`]. Both answer the same `call(tick, input)`.

use std::fmt::Debug;

use iceoryx2::prelude::ZeroCopySend;
use plamo_interfaces::{Component, Tick};

use super::RunError;
use crate::ipc::RemoteComponent;

/// One component instance as the lockstep sees it.
pub trait Link<I, O> {
    /// Instance name for errors (`physics`, `planner-0`, `controller-1`).
    fn name(&self) -> &str;
    /// Step the component at `tick` with `input`.
    fn call(&mut self, tick: u64, input: &I) -> Result<O, RunError>;
    /// Ask the component to stop (a component process exits; in-process: nothing).
    fn shutdown(&mut self) {}
}

/// A component stepped directly.
pub struct InProcess<C: Component> {
    name: String,
    /// The component (public so callers can read its rich state, e.g. the plan).
    pub component: C,
}

impl<C: Component> InProcess<C> {
    /// Wrap `component` under instance name `name`.
    pub fn new(name: impl Into<String>, component: C) -> Self {
        Self {
            name: name.into(),
            component,
        }
    }
}

impl<C> Link<C::Input, C::Output> for InProcess<C>
where
    C: Component,
    C::Output: Default,
{
    fn name(&self) -> &str {
        &self.name
    }
    fn call(&mut self, tick: u64, input: &C::Input) -> Result<C::Output, RunError> {
        let mut out = C::Output::default();
        self.component
            .step(Tick(tick), input, &mut out)
            .map_err(|source| RunError::Component {
                component: self.name.clone(),
                tick,
                source,
            })?;
        Ok(out)
    }
}

impl<I, O> Link<I, O> for RemoteComponent<I, O>
where
    I: ZeroCopySend + Copy + Debug + Default + 'static,
    O: ZeroCopySend + Copy + Debug + Default + 'static,
{
    fn name(&self) -> &str {
        RemoteComponent::name(self)
    }
    fn call(&mut self, tick: u64, input: &I) -> Result<O, RunError> {
        Ok(RemoteComponent::call(self, tick, input)?)
    }
    fn shutdown(&mut self) {
        // A component that is already gone cannot be told; the caller reaps it.
        let _ = RemoteComponent::shutdown(self);
    }
}
