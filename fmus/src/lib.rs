//! PlaMo as an FMI 2.0 co-simulation FMU.
