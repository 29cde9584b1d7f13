//! Service naming per run. Every service of a run lives under `plamo/<run id>/`, so
//! two runs on one machine never see each other's messages.

use std::fmt;

/// The three component kinds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ComponentKind {
    /// The path planner (one per agent).
    Planner,
    /// The locomotion controller (one per agent).
    Controller,
    /// The physics world (one per run).
    Physics,
}

impl ComponentKind {
    /// All kinds, in lockstep order.
    pub const ALL: [ComponentKind; 3] = [
        ComponentKind::Planner,
        ComponentKind::Controller,
        ComponentKind::Physics,
    ];

    /// Lower-case name used on the command line and in service names.
    pub fn as_str(self) -> &'static str {
        match self {
            ComponentKind::Planner => "planner",
            ComponentKind::Controller => "controller",
            ComponentKind::Physics => "physics",
        }
    }
}

impl fmt::Display for ComponentKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for ComponentKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|k| k.as_str() == s)
            .ok_or_else(|| {
                format!("unknown component `{s}`; expected one of: planner, controller, physics")
            })
    }
}

/// A run identifier: 1-32 characters of `[a-z0-9-]`, used in service names and as
/// the iceoryx2 prefix that isolates concurrent runs.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct RunId(String);

impl RunId {
    /// Validate a run id.
    pub fn new(id: &str) -> Result<Self, String> {
        let ok = !id.is_empty()
            && id.len() <= 32
            && id
                .bytes()
                .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'-');
        if ok {
            Ok(Self(id.to_owned()))
        } else {
            Err(format!(
                "invalid run id `{id}`: use 1-32 characters of a-z, 0-9 and '-'"
            ))
        }
    }

    /// The id as text.
    pub fn as_str(&self) -> &str {
        &self.0
    }
}

impl fmt::Display for RunId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

/// The services one component instance uses: a request channel (orchestrator to
/// component), a response channel (component to orchestrator), and one event for each
/// direction, because iceoryx2 pub/sub has no blocking receive.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServiceNames {
    /// Orchestrator to component payloads.
    pub request: String,
    /// Component to orchestrator payloads.
    pub response: String,
    /// "A request is waiting" event.
    pub request_event: String,
    /// "A response is waiting" event.
    pub response_event: String,
}

impl ServiceNames {
    /// Names for `kind` (instance `agent` for per-agent components) in run `run`.
    pub fn new(run: &RunId, kind: ComponentKind, agent: u32) -> Self {
        let base = match kind {
            ComponentKind::Physics => format!("plamo/{run}/physics"),
            _ => format!("plamo/{run}/{kind}/{agent}"),
        };
        Self {
            request: format!("{base}/request"),
            response: format!("{base}/response"),
            request_event: format!("{base}/request-event"),
            response_event: format!("{base}/response-event"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_ids_are_validated_and_names_are_disjoint() {
        assert!(RunId::new("run-42").is_ok());
        for bad in ["", "Has Caps", "a/b", &"x".repeat(33)] {
            assert!(RunId::new(bad).is_err(), "{bad}");
        }
        let a = RunId::new("a").unwrap();
        let b = RunId::new("b").unwrap();
        let p0 = ServiceNames::new(&a, ComponentKind::Planner, 0);
        let p1 = ServiceNames::new(&a, ComponentKind::Planner, 1);
        let q0 = ServiceNames::new(&b, ComponentKind::Planner, 0);
        assert_ne!(p0, p1);
        assert_ne!(p0, q0);
        assert_eq!(p0.request, "plamo/a/planner/0/request");
        assert_eq!(
            "physics".parse::<ComponentKind>(),
            Ok(ComponentKind::Physics)
        );
        assert!(
            "phys"
                .parse::<ComponentKind>()
                .unwrap_err()
                .contains("planner, controller, physics")
        );
    }
}
