//! Render streams: several renderers, each on a device of its own, rendering side by side.
//!
//! A software rasteriser leaves cores idle within and between one renderer's dispatches
//! (and while it records, submits and reads back); renderers on other devices fill them.
//! A [`RenderPool`] holds those renderers and runs a sequence of submissions on them:
//! submission `c` goes to stream `c mod N`, always, and the results come back in
//! submission order. The fixed assignment makes a pool's output a function of its input
//! even where a renderer's output depends on what it rendered before (its sensor noise is
//! drawn from its own frame counter).
//!
//! The submissions are produced on a thread of their own (so preparing the next one overlaps
//! rendering this one), each stream renders on a thread of its own, and the results are
//! handed over on the calling thread. A stream's error stops the run and is returned; a
//! panic in a stream or in the producer becomes a [`GeltipError`].

use crate::error::{GeltipError, Result};
use crate::object::Object;
use crate::render::gpu::Renderer;
use crate::sensor::Sensor;
use std::any::Any;
use std::collections::BTreeMap;
use std::sync::mpsc;
use std::sync::Arc;
use std::thread::ScopedJoinHandle;

/// Renderers that render submissions side by side: stream `i` is `streams()[i]`.
/// Generic over the stream type so the scheduling can be tested without a GPU.
pub struct RenderPool<R = Renderer> {
    streams: Vec<R>,
}

impl RenderPool<Renderer> {
    /// Starts `streams` renderers of `sensor` side by side, each on a device of its own
    /// ([`crate::gpu::GpuContext::stream`]) with the contact pipelines of `objects` built.
    pub fn start(sensor: &Sensor, streams: usize, objects: &[Arc<Object>]) -> Result<RenderPool> {
        RenderPool::new(Renderer::on_streams(sensor, streams, objects)?)
    }
}

impl RenderPool<Renderer> {
    /// Frames a submission of this pool takes: what its users chunk their work by (the
    /// streams' [`Renderer::batch_frames`], the smallest if they differ).
    pub fn batch_frames(&self) -> usize {
        self.streams
            .iter()
            .map(Renderer::batch_frames)
            .min()
            .unwrap_or(1)
    }

    /// Sets every stream's frames a submission ([`Renderer::set_batch_frames`]).
    pub fn set_batch_frames(&mut self, frames: usize) -> Result<()> {
        for stream in &mut self.streams {
            stream.set_batch_frames(frames)?;
        }
        Ok(())
    }
}

impl<R: Send> RenderPool<R> {
    /// A pool of the given streams (at least one).
    pub fn new(streams: Vec<R>) -> Result<RenderPool<R>> {
        if streams.is_empty() {
            return Err(GeltipError::input(
                "render streams",
                "a pool needs at least one",
            ));
        }
        Ok(RenderPool { streams })
    }

    /// The streams, stream 0 first.
    pub fn streams(&self) -> &[R] {
        &self.streams
    }

    /// The streams, mutably (to render on one of them outside a run).
    pub fn streams_mut(&mut self) -> &mut [R] {
        &mut self.streams
    }

    /// Stream 0: the one to ask for what every stream shares (sensor, reference frame).
    pub fn first(&self) -> &R {
        &self.streams[0]
    }

    /// Gives the streams back.
    pub fn into_streams(self) -> Vec<R> {
        self.streams
    }

    /// Runs `work` on every submission of `jobs`, submission `c` on stream `c mod N`, and
    /// hands each result to `deliver` in submission order, on this thread. `jobs` is
    /// iterated on a thread of its own, at most one submission ahead of each stream.
    ///
    /// Stops at the first error (of `work` or of `deliver`) and returns it; the streams
    /// finish the submission they are rendering and take no other. Results of submissions
    /// after a failed one are not delivered.
    pub fn run<I, T, W, D>(&mut self, jobs: I, work: W, mut deliver: D) -> Result<()>
    where
        I: IntoIterator,
        I::IntoIter: Send,
        I::Item: Send,
        T: Send,
        W: Fn(&mut R, I::Item) -> Result<T> + Sync,
        D: FnMut(T) -> Result<()>,
    {
        let n = self.streams.len();
        let (done_tx, done_rx) = mpsc::sync_channel::<(usize, Result<T>)>(n);
        let (queues, inboxes): (Vec<_>, Vec<_>) = (0..n)
            .map(|_| mpsc::sync_channel::<(usize, I::Item)>(1))
            .unzip();
        let jobs = jobs.into_iter();
        std::thread::scope(|scope| {
            // The producer stops at the first stream that stops taking submissions, and its
            // leaving closes every stream's queue.
            let producer = scope.spawn(move || {
                for (c, job) in jobs.enumerate() {
                    if queues[c % n].send((c, job)).is_err() {
                        return;
                    }
                }
            });
            let work = &work;
            let streams: Vec<_> = self
                .streams
                .iter_mut()
                .zip(inboxes)
                .map(|(stream, inbox)| {
                    let done = done_tx.clone();
                    scope.spawn(move || {
                        for (c, job) in inbox {
                            let result = work(stream, job);
                            let failed = result.is_err();
                            if done.send((c, result)).is_err() || failed {
                                return;
                            }
                        }
                    })
                })
                .collect();
            drop(done_tx);
            // Owned here, so that a panic in `deliver` drops it too and no stream waits on
            // it while the scope joins them.
            let done_rx = done_rx;
            let delivered = deliver_in_order(&done_rx, &mut deliver);
            // Streams blocked on handing over a result see the channel closed and stop.
            drop(done_rx);
            let panicked = join_all(streams, producer);
            match (delivered, panicked) {
                (Err(e), _) | (Ok(()), Some(e)) => Err(e),
                (Ok(()), None) => Ok(()),
            }
        })
    }

    /// [`RenderPool::run`], collecting the results in submission order.
    pub fn map<I, T, W>(&mut self, jobs: I, work: W) -> Result<Vec<T>>
    where
        I: IntoIterator,
        I::IntoIter: Send,
        I::Item: Send,
        T: Send,
        W: Fn(&mut R, I::Item) -> Result<T> + Sync,
    {
        let mut out = Vec::new();
        self.run(jobs, work, |t| {
            out.push(t);
            Ok(())
        })?;
        Ok(out)
    }
}

/// Receives the streams' results until every stream has stopped, handing them to `deliver`
/// in submission order; stops at the first error.
fn deliver_in_order<T>(
    done: &mpsc::Receiver<(usize, Result<T>)>,
    deliver: &mut impl FnMut(T) -> Result<()>,
) -> Result<()> {
    let mut next = 0;
    let mut waiting = BTreeMap::new();
    for (c, result) in done {
        waiting.insert(c, result?);
        while let Some(t) = waiting.remove(&next) {
            deliver(t)?;
            next += 1;
        }
    }
    Ok(())
}

/// Joins the streams' threads and the producer's: the first panic, as an error.
fn join_all(
    streams: Vec<ScopedJoinHandle<'_, ()>>,
    producer: ScopedJoinHandle<'_, ()>,
) -> Option<GeltipError> {
    let mut panicked = None;
    for (i, stream) in streams.into_iter().enumerate() {
        if let Err(payload) = stream.join() {
            panicked.get_or_insert_with(|| {
                GeltipError::Gpu(format!(
                    "render stream {i} panicked: {}",
                    panic_message(&*payload)
                ))
            });
        }
    }
    if let Err(payload) = producer.join() {
        panicked.get_or_insert_with(|| {
            GeltipError::Gpu(format!(
                "preparing the render streams' submissions panicked: {}",
                panic_message(&*payload)
            ))
        });
    }
    panicked
}

fn panic_message(payload: &(dyn Any + Send)) -> &str {
    payload
        .downcast_ref::<&str>()
        .copied()
        .or_else(|| payload.downcast_ref::<String>().map(String::as_str))
        .unwrap_or("no message")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stream that records what it rendered.
    #[derive(Default)]
    struct Recorder {
        rendered: Vec<usize>,
    }

    fn pool(n: usize) -> RenderPool<Recorder> {
        RenderPool::new((0..n).map(|_| Recorder::default()).collect()).unwrap()
    }

    #[test]
    fn submissions_go_to_c_mod_n_and_come_back_in_order() {
        for n in 1..=4 {
            let mut p = pool(n);
            let out = p
                .map(0..23usize, |s, c| {
                    // Later submissions finish first on some streams.
                    std::thread::sleep(std::time::Duration::from_micros(
                        ((c * 7) % 5) as u64 * 200,
                    ));
                    s.rendered.push(c);
                    Ok(c * 10)
                })
                .unwrap();
            assert_eq!(out, (0..23).map(|c| c * 10).collect::<Vec<_>>());
            for (i, s) in p.streams().iter().enumerate() {
                let expected: Vec<usize> = (0..23).filter(|c| c % n == i).collect();
                assert_eq!(s.rendered, expected, "stream {i} of {n}");
            }
        }
    }

    #[test]
    fn the_first_error_stops_the_run() {
        let mut p = pool(3);
        let mut delivered = Vec::new();
        let e = p
            .run(
                0..1000usize,
                |s, c| {
                    s.rendered.push(c);
                    if c == 7 {
                        Err(GeltipError::input("submission 7", "failed"))
                    } else {
                        Ok(c)
                    }
                },
                |c| {
                    delivered.push(c);
                    Ok(())
                },
            )
            .unwrap_err();
        assert_eq!(e.to_string(), "submission 7: failed");
        assert!(delivered.iter().all(|&c| c < 7), "{delivered:?}");
        let rendered: usize = p.streams().iter().map(|s| s.rendered.len()).sum();
        assert!(
            rendered < 20,
            "{rendered} submissions rendered after the error"
        );

        let e = p
            .run(
                0..1000usize,
                |_, c| Ok(c),
                |c| {
                    if c == 5 {
                        Err(GeltipError::input("delivery", "refused"))
                    } else {
                        Ok(())
                    }
                },
            )
            .unwrap_err();
        assert_eq!(e.to_string(), "delivery: refused");
    }

    #[test]
    fn panics_become_errors() {
        let mut p = pool(2);
        let e = p
            .map(0..10usize, |_, c| {
                if c == 3 {
                    panic!("stream broke at {c}");
                }
                Ok(c)
            })
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "gpu: render stream 1 panicked: stream broke at 3"
        );
        let jobs = (0..10usize).inspect(|&c| assert!(c < 4, "no submission {c}"));
        let e = p.map(jobs, |_, c| Ok(c)).unwrap_err();
        assert!(
            e.to_string()
                .contains("submissions panicked: no submission 4"),
            "{e}"
        );
        // A panic where the results are handed over is the caller's: it propagates, and
        // no stream is left waiting.
        let caught = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            p.run(
                0..100usize,
                |_, c| Ok(c),
                |c| {
                    assert!(c < 3, "delivery broke at {c}");
                    Ok(())
                },
            )
        }));
        assert!(caught.is_err());
        // The pool is usable after a failed run.
        assert_eq!(p.map(0..3usize, |_, c| Ok(c)).unwrap(), vec![0, 1, 2]);
    }

    #[test]
    fn an_empty_pool_is_refused() {
        assert!(RenderPool::<Recorder>::new(Vec::new()).is_err());
    }
}
