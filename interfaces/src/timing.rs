//! Simulated time. Time is an integer tick at 120 Hz, never an accumulated float, so
//! every component agrees on "now" bit for bit.

/// Physics rate \[Hz\] (paper 5.1: simulated at 120 Hz).
pub const PHYSICS_HZ: u32 = 120;
/// Control rate \[Hz\] (paper 5.1: the controller decides at 30 Hz).
pub const CONTROL_HZ: u32 = 30;
/// Physics steps per control step.
pub const PHYSICS_STEPS_PER_CONTROL: u32 = PHYSICS_HZ / CONTROL_HZ;
/// One physics step \[s\].
pub const PHYSICS_DT: f64 = 1.0 / PHYSICS_HZ as f64;
/// One control step \[s\].
pub const CONTROL_DT: f64 = 1.0 / CONTROL_HZ as f64;

/// A physics tick: t = tick / 120 s.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
#[repr(transparent)]
pub struct Tick(pub u64);

impl Tick {
    /// Simulated time of this tick \[s\].
    pub fn seconds(self) -> f64 {
        self.0 as f64 / PHYSICS_HZ as f64
    }
    /// Whether a control step happens on this tick (every 4th tick).
    pub fn is_control(self) -> bool {
        self.0.is_multiple_of(PHYSICS_STEPS_PER_CONTROL as u64)
    }
    /// The tick `n` physics steps later.
    pub fn advanced(self, n: u64) -> Tick {
        Tick(self.0 + n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn four_physics_steps_per_control_step() {
        assert_eq!(PHYSICS_STEPS_PER_CONTROL, 4);
        let control: Vec<u64> = (0..13)
            .map(Tick)
            .filter(|t| t.is_control())
            .map(|t| t.0)
            .collect();
        assert_eq!(control, vec![0, 4, 8, 12]);
        assert_eq!(Tick(120).seconds(), 1.0);
    }
}
