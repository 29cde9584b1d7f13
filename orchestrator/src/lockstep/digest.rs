//! A 64-bit fingerprint (FNV-1a) of every world state a run went through, over the
//! exact bit patterns of every reported number: equal digests mean bit-identical
//! trajectories.

use plamo_interfaces::PhysicsOutput;

/// Running FNV-1a hash of world states.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Digest(u64);

impl Default for Digest {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl Digest {
    fn word(&mut self, w: u64) {
        for b in w.to_le_bytes() {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }

    fn floats(&mut self, v: &[f64]) {
        for x in v {
            self.word(x.to_bits());
        }
    }

    /// Fold one world state (every valid agent and obstacle) into the hash.
    pub fn add(&mut self, w: &PhysicsOutput) {
        self.word(w.tick);
        self.word(w.agent_count as u64);
        for s in &w.agents[..(w.agent_count as usize).min(w.agents.len())] {
            self.floats(&s.root_position);
            self.floats(&s.root_orientation);
            self.floats(&s.root_linear_velocity);
            self.floats(&s.root_angular_velocity);
            self.floats(&s.head_position);
            self.floats(&s.joint_angles);
            self.floats(&s.joint_velocities);
            for p in &s.body_positions {
                self.floats(p);
            }
            self.word(((s.body_contacts as u64) << 32) | s.fallen as u64);
        }
        for o in &w.obstacles[..(w.obstacle_count as usize).min(w.obstacles.len())] {
            self.floats(&o.position);
            self.floats(&o.velocity);
        }
    }

    /// The hash value.
    pub fn value(&self) -> u64 {
        self.0
    }
}
