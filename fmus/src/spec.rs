//! What an FMU exposes: its variables, one table per model, which is the single
//! source for `modelDescription.xml` and for the get/set dispatch of the binary.

use std::fmt::Write;

/// FMI base type of a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VarType {
    /// fmi2Real.
    Real,
    /// fmi2Integer.
    Integer,
    /// fmi2Boolean.
    Boolean,
    /// fmi2String.
    String,
}

impl VarType {
    fn xml(self) -> &'static str {
        match self {
            VarType::Real => "Real",
            VarType::Integer => "Integer",
            VarType::Boolean => "Boolean",
            VarType::String => "String",
        }
    }
}

/// FMI causality (the subset PlaMo uses).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Causality {
    /// Set before initialisation, fixed afterwards.
    Parameter,
    /// Set by the host between steps.
    Input,
    /// Computed by the FMU.
    Output,
}

/// One FMU variable. Its value reference is its index in [`ModelSpec::variables`].
#[derive(Debug, Clone, PartialEq)]
pub struct Variable {
    /// Structured name (`head.x`, `joint[3]`).
    pub name: String,
    /// Base type.
    pub ty: VarType,
    /// Causality.
    pub causality: Causality,
    /// One-line description.
    pub description: String,
    /// Start value as text (required for parameters and inputs).
    pub start: Option<String>,
    /// Unit name from the unit definitions (`m`, `m/s`, `rad`), if any.
    pub unit: Option<&'static str>,
}

impl Variable {
    fn new(
        name: impl Into<String>,
        ty: VarType,
        causality: Causality,
        description: impl Into<String>,
    ) -> Self {
        Self {
            name: name.into(),
            ty,
            causality,
            description: description.into(),
            start: None,
            unit: None,
        }
    }

    /// A parameter with a start value.
    pub fn parameter(
        name: impl Into<String>,
        ty: VarType,
        start: impl Into<String>,
        description: impl Into<String>,
    ) -> Self {
        Self {
            start: Some(start.into()),
            ..Self::new(name, ty, Causality::Parameter, description)
        }
    }

    /// A Real input starting at `start`.
    pub fn real_input(
        name: impl Into<String>,
        start: f64,
        unit: Option<&'static str>,
        description: impl Into<String>,
    ) -> Self {
        Self {
            start: Some(format!("{start:?}")),
            unit,
            ..Self::new(name, VarType::Real, Causality::Input, description)
        }
    }

    /// An input of any type starting at `start`.
    pub fn input(
        name: impl Into<String>,
        ty: VarType,
        start: impl Into<String>,
        unit: Option<&'static str>,
        description: impl Into<String>,
    ) -> Self {
        Self {
            start: Some(start.into()),
            unit,
            ..Self::new(name, ty, Causality::Input, description)
        }
    }

    /// An output.
    pub fn output(
        name: impl Into<String>,
        ty: VarType,
        unit: Option<&'static str>,
        description: impl Into<String>,
    ) -> Self {
        Self {
            unit,
            ..Self::new(name, ty, Causality::Output, description)
        }
    }

    fn variability(&self) -> &'static str {
        match (self.causality, self.ty) {
            (Causality::Parameter, _) => "fixed",
            (_, VarType::Real) => "continuous",
            _ => "discrete",
        }
    }
}

/// Units used by the variables, declared once in the model description.
pub const UNITS: &[(&str, &str)] = &[
    ("m", "<BaseUnit m=\"1\"/>"),
    ("m/s", "<BaseUnit m=\"1\" s=\"-1\"/>"),
    ("rad", "<BaseUnit rad=\"1\"/>"),
    ("1", ""),
];

/// An FMU's identity and variables.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelSpec {
    /// `modelName`.
    pub model_name: &'static str,
    /// `modelIdentifier`: the shared library's file name without extension.
    pub model_identifier: &'static str,
    /// `guid`; checked in fmi2Instantiate.
    pub guid: &'static str,
    /// One-line description.
    pub description: &'static str,
    /// The variables; value reference = index.
    pub variables: Vec<Variable>,
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

impl ModelSpec {
    /// Value reference of the variable called `name`.
    pub fn vr(&self, name: &str) -> Option<u32> {
        self.variables
            .iter()
            .position(|v| v.name == name)
            .map(|i| i as u32)
    }

    /// The `modelDescription.xml` text (FMI 2.0, co-simulation).
    pub fn model_description_xml(&self) -> String {
        let mut x = String::new();
        let _ = writeln!(x, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
        let _ = writeln!(
            x,
            r#"<fmiModelDescription fmiVersion="2.0" modelName="{}" guid="{}" description="{}" generationTool="plamo {}" variableNamingConvention="structured" numberOfEventIndicators="0">"#,
            escape(self.model_name),
            self.guid,
            escape(self.description),
            env!("CARGO_PKG_VERSION")
        );
        let _ = writeln!(
            x,
            r#"  <CoSimulation modelIdentifier="{}" canHandleVariableCommunicationStepSize="true" canBeInstantiatedOnlyOncePerProcess="false" canNotUseMemoryManagementFunctions="true" canGetAndSetFMUstate="false" canSerializeFMUstate="false"/>"#,
            self.model_identifier
        );
        let used: Vec<&str> = UNITS
            .iter()
            .map(|(n, _)| *n)
            .filter(|n| self.variables.iter().any(|v| v.unit == Some(n)))
            .collect();
        if !used.is_empty() {
            let _ = writeln!(x, "  <UnitDefinitions>");
            for (name, base) in UNITS.iter().filter(|(n, _)| used.contains(n)) {
                if base.is_empty() {
                    let _ = writeln!(x, r#"    <Unit name="{name}"/>"#);
                } else {
                    let _ = writeln!(x, r#"    <Unit name="{}">{base}</Unit>"#, escape(name));
                }
            }
            let _ = writeln!(x, "  </UnitDefinitions>");
        }
        let _ = writeln!(
            x,
            r#"  <DefaultExperiment startTime="0.0" stepSize="0.03333333333333333"/>"#
        );
        let _ = writeln!(x, "  <ModelVariables>");
        for (vr, v) in self.variables.iter().enumerate() {
            let causality = match v.causality {
                Causality::Parameter => "parameter",
                Causality::Input => "input",
                Causality::Output => "output",
            };
            let initial = match v.causality {
                Causality::Parameter => r#" initial="exact""#,
                Causality::Output => r#" initial="calculated""#,
                Causality::Input => "",
            };
            let _ = writeln!(
                x,
                r#"    <ScalarVariable name="{}" valueReference="{vr}" description="{}" causality="{causality}" variability="{}"{initial}>"#,
                escape(&v.name),
                escape(&v.description),
                v.variability()
            );
            let mut attrs = String::new();
            if let Some(s) = &v.start {
                let _ = write!(attrs, r#" start="{}""#, escape(s));
            }
            if let Some(u) = v.unit {
                let _ = write!(attrs, r#" unit="{}""#, escape(u));
            }
            let _ = writeln!(x, "      <{}{attrs}/>", v.ty.xml());
            let _ = writeln!(x, "    </ScalarVariable>");
        }
        let _ = writeln!(x, "  </ModelVariables>");
        let _ = writeln!(x, "  <ModelStructure>");
        let outputs: Vec<usize> = self
            .variables
            .iter()
            .enumerate()
            .filter(|(_, v)| v.causality == Causality::Output)
            .map(|(i, _)| i + 1)
            .collect();
        for section in ["Outputs", "InitialUnknowns"] {
            let _ = writeln!(x, "    <{section}>");
            for i in &outputs {
                let _ = writeln!(x, r#"      <Unknown index="{i}"/>"#);
            }
            let _ = writeln!(x, "    </{section}>");
        }
        let _ = writeln!(x, "  </ModelStructure>");
        let _ = writeln!(x, "</fmiModelDescription>");
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn description_lists_every_variable_and_output_indices() {
        let spec = ModelSpec {
            model_name: "m",
            model_identifier: "m",
            guid: "{g}",
            description: "a & b",
            variables: vec![
                Variable::parameter("scene", VarType::String, "play<ground>", "scene"),
                Variable::real_input("obstacle[1].x", 0.0, Some("m"), "x"),
                Variable::output("head.z", VarType::Real, Some("m"), "z"),
            ],
        };
        let xml = spec.model_description_xml();
        assert!(xml.contains(r#"name="scene" valueReference="0""#));
        assert!(xml.contains(r#"start="play&lt;ground&gt;""#));
        assert!(xml.contains(r#"description="a &amp; b""#));
        assert!(xml.contains(r#"<Unknown index="3"/>"#));
        assert!(!xml.contains(r#"<Unknown index="2"/>"#));
        assert_eq!(spec.vr("head.z"), Some(2));
    }
}
