//! The frame around every payload: its tick, what kind of frame it is, and room for
//! an error message, all in shared memory.

use iceoryx2::prelude::*;

/// Longest error text carried back from a component \[bytes\].
pub const ERROR_CAPACITY: usize = 512;

/// What an [`Envelope`] carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
pub enum EnvelopeKind {
    /// A request or a response with a payload.
    Data = 0,
    /// The component's ports exist and it waits for requests.
    Ready = 1,
    /// The component's step failed; the text says why.
    Error = 2,
    /// The orchestrator is done; the component should exit.
    Shutdown = 3,
}

impl EnvelopeKind {
    fn from_u32(v: u32) -> Option<Self> {
        [Self::Data, Self::Ready, Self::Error, Self::Shutdown]
            .into_iter()
            .find(|k| *k as u32 == v)
    }
}

/// A payload framed with its tick and kind.
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[repr(C)]
pub struct Envelope<T: ZeroCopySend + Copy> {
    /// The tick the payload belongs to.
    pub tick: u64,
    /// An [`EnvelopeKind`] as u32 (an enum read from shared memory must be checked).
    pub kind: u32,
    /// Valid bytes of `error`.
    pub error_len: u32,
    /// UTF-8 text: the error for [`EnvelopeKind::Error`], the component's identity
    /// (what run it was started for) for [`EnvelopeKind::Ready`].
    pub error: [u8; ERROR_CAPACITY],
    /// The message.
    pub payload: T,
}

impl<T: ZeroCopySend + Copy + Default> Envelope<T> {
    /// A frame of `kind` at `tick` around `payload`.
    pub fn new(kind: EnvelopeKind, tick: u64, payload: T) -> Self {
        Self {
            tick,
            kind: kind as u32,
            error_len: 0,
            error: [0; ERROR_CAPACITY],
            payload,
        }
    }

    /// An error frame; the text is cut at a character boundary to fit.
    pub fn error(tick: u64, text: &str) -> Self {
        Self::with_text(EnvelopeKind::Error, tick, text)
    }

    /// A ready frame carrying the component's identity.
    pub fn ready(tick: u64, identity: &str) -> Self {
        Self::with_text(EnvelopeKind::Ready, tick, identity)
    }

    fn with_text(kind: EnvelopeKind, tick: u64, text: &str) -> Self {
        let mut e = Self::new(kind, tick, T::default());
        let mut n = text.len().min(ERROR_CAPACITY);
        while !text.is_char_boundary(n) {
            n -= 1;
        }
        e.error[..n].copy_from_slice(&text.as_bytes()[..n]);
        e.error_len = n as u32;
        e
    }

    /// The frame's kind, or `None` for a value no peer of ours writes.
    pub fn kind(&self) -> Option<EnvelopeKind> {
        EnvelopeKind::from_u32(self.kind)
    }

    /// The error text.
    pub fn error_text(&self) -> String {
        let n = (self.error_len as usize).min(ERROR_CAPACITY);
        String::from_utf8_lossy(&self.error[..n]).into_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_text_round_trips_and_is_cut_on_a_char_boundary() {
        let e = Envelope::<u64>::error(7, "physics: NaN in joint 3");
        assert_eq!(e.kind(), Some(EnvelopeKind::Error));
        assert_eq!(e.error_text(), "physics: NaN in joint 3");
        let long = "é".repeat(ERROR_CAPACITY);
        let e = Envelope::<u64>::error(0, &long);
        assert!(e.error_len as usize <= ERROR_CAPACITY);
        assert!(e.error_text().chars().all(|c| c == 'é'));
        let mut bad = Envelope::<u64>::new(EnvelopeKind::Data, 0, 0);
        bad.kind = 99;
        assert_eq!(bad.kind(), None);
    }
}
