//! The orchestrator's handle on one component process.

use std::fmt::Debug;
use std::time::Instant;

use iceoryx2::prelude::*;
use plamo_interfaces::ServiceNames;

use super::envelope::{Envelope, EnvelopeKind};
use super::error::IpcError;
use super::setup::{Channels, IpcSettings};

/// Returns `Some(reason)` once the peer is known to be dead.
pub type LivenessCheck = Box<dyn FnMut() -> Option<String> + Send>;

/// A component in another process, called like the in-process one.
pub struct RemoteComponent<I, O>
where
    I: ZeroCopySend + Copy + Debug + Default + 'static,
    O: ZeroCopySend + Copy + Debug + Default + 'static,
{
    name: String,
    channels: Channels<I, O>,
    settings: IpcSettings,
    liveness: LivenessCheck,
}

impl<I, O> RemoteComponent<I, O>
where
    I: ZeroCopySend + Copy + Debug + Default + 'static,
    O: ZeroCopySend + Copy + Debug + Default + 'static,
{
    /// Open this side of the link. Do it before the component process starts so its
    /// ready frame is not lost (it repeats it anyway).
    pub fn open(
        node: &Node<ipc::Service>,
        name: impl Into<String>,
        names: &ServiceNames,
        settings: IpcSettings,
        liveness: LivenessCheck,
    ) -> Result<Self, IpcError> {
        let channels = Channels::open(
            node,
            &names.request,
            &names.response,
            &names.request_event,
            &names.response_event,
        )?;
        Ok(Self {
            name: name.into(),
            channels,
            settings,
            liveness,
        })
    }

    /// The component's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Wait for the component's ready frame; it must carry `identity` (the run the
    /// component was built for), else [`IpcError::Mismatch`].
    pub fn wait_ready(&mut self, identity: &str) -> Result<(), IpcError> {
        let start = Instant::now();
        loop {
            if let Some(frame) = self.channels.receive_within(self.settings.slice)? {
                if frame.kind() == Some(EnvelopeKind::Ready) {
                    let got = frame.error_text();
                    if got != identity {
                        return Err(IpcError::Mismatch {
                            component: self.name.clone(),
                            expected: identity.to_owned(),
                            got,
                        });
                    }
                    // Drain duplicates so they don't precede the first response.
                    while self.channels.try_receive()?.is_some() {}
                    return Ok(());
                }
                continue;
            }
            self.check_alive(0)?;
            if start.elapsed() > self.settings.ready_timeout {
                return Err(IpcError::Timeout {
                    component: self.name.clone(),
                    tick: 0,
                    timeout: self.settings.ready_timeout,
                });
            }
        }
    }

    fn check_alive(&mut self, tick: u64) -> Result<(), IpcError> {
        match (self.liveness)() {
            Some(detail) => Err(IpcError::PeerDied {
                component: self.name.clone(),
                tick,
                detail,
            }),
            None => Ok(()),
        }
    }

    /// Send `input` for `tick` and wait for the component's output for that tick.
    /// Wall-clock time only bounds the wait; it never changes what is computed.
    pub fn call(&mut self, tick: u64, input: &I) -> Result<O, IpcError> {
        self.channels
            .send(Envelope::new(EnvelopeKind::Data, tick, *input))?;
        let start = Instant::now();
        let mut checked = start;
        let mut polled = self.channels.poll_within(self.settings.poll)?;
        loop {
            let received = match polled.take() {
                Some(frame) => Some(frame),
                None => self.channels.receive_within(self.settings.slice)?,
            };
            match received {
                Some(frame) => match frame.kind() {
                    Some(EnvelopeKind::Ready) => continue,
                    Some(EnvelopeKind::Data) if frame.tick == tick => return Ok(frame.payload),
                    Some(EnvelopeKind::Data) => {
                        return Err(IpcError::WrongTick {
                            component: self.name.clone(),
                            expected: tick,
                            got: frame.tick,
                        });
                    }
                    Some(EnvelopeKind::Error) => {
                        return Err(IpcError::Component {
                            component: self.name.clone(),
                            tick,
                            message: frame.error_text(),
                        });
                    }
                    _ => {
                        return Err(IpcError::Malformed {
                            component: self.name.clone(),
                            kind: frame.kind,
                        });
                    }
                },
                // A wake-up without a frame is usually the notification of a frame
                // already taken; listing the nodes costs more than a fast reply, so
                // liveness is checked once per slice of waiting.
                None if checked.elapsed() < self.settings.slice / 2 => {}
                None => {
                    checked = Instant::now();
                    self.check_alive(tick)?;
                    if start.elapsed() > self.settings.call_timeout {
                        return Err(IpcError::Timeout {
                            component: self.name.clone(),
                            tick,
                            timeout: self.settings.call_timeout,
                        });
                    }
                }
            }
        }
    }

    /// Tell the component to exit.
    pub fn shutdown(&self) -> Result<(), IpcError> {
        self.channels.signal(EnvelopeKind::Shutdown, 0)
    }
}
