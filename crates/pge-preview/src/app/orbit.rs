//! `--orbit-frames`: the viewport measured without a person.

use std::time::{Duration, Instant};

use crate::render::FrameTimes;

/// `--orbit-frames N`: once the first model is on screen, the camera turns once around it in
/// N frames drawn as moving ones, then rests until a frame at full quality is drawn with its
/// final forest plan; every frame's times go to stderr, then a summary.
pub(super) struct Orbit {
    pub frames: u32,
    /// Moving frames drawn so far.
    turned: u32,
    /// How long the window's update of the last moving frame took (the viewport's drawing
    /// and the panel's layout; the rest of a frame is egui's painting and presenting).
    update: Option<Duration>,
    /// Start of each moving frame.
    starts: Vec<Instant>,
    /// When the resting frames began, and whether the last one drew the final plan.
    rest: Option<(Instant, bool)>,
    /// CPU time of the whole process (every thread) when the turn began and ended.
    cpu: (Option<Duration>, Option<Duration>),
}

/// CPU time the process has used so far, over all its threads (Linux: the sum of
/// `/proc/self/task/*/schedstat`); `None` elsewhere.
fn process_cpu() -> Option<Duration> {
    let mut total = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let text = std::fs::read_to_string(task.ok()?.path().join("schedstat")).ok()?;
        total += text.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(Duration::from_nanos(total))
}

impl Orbit {
    pub fn new(frames: u32) -> Orbit {
        Orbit {
            frames,
            turned: 0,
            update: None,
            starts: Vec::new(),
            rest: None,
            cpu: (None, None),
        }
    }

    pub fn finished(&self) -> bool {
        self.rest.is_some_and(|(_, done)| done)
    }

    /// A frame starts: whether it is a moving one, and whether it must be drawn (every
    /// moving frame and the first resting one; the next resting ones when a plan arrives).
    pub fn next_frame(&mut self, now: Instant) -> (bool, bool) {
        if self.turned < self.frames {
            if self.turned == 0 {
                self.cpu.0 = process_cpu();
            }
            self.turned += 1;
            self.starts.push(now);
            return (true, true);
        }
        let first_rest = self.rest.is_none();
        if first_rest {
            self.rest = Some((now, false));
            self.cpu.1 = process_cpu();
        }
        (false, first_rest)
    }

    /// The window's update of the frame took `took`.
    pub fn updated(&mut self, took: Duration) {
        if self.turning() || self.rest.is_none() {
            self.update = Some(took);
        }
    }

    /// Ends the orbit without turning (there is no model).
    pub fn abandon(&mut self) {
        self.turned = self.frames;
        self.rest = Some((Instant::now(), true));
    }

    /// Still turning: frames follow one another without waiting for anything.
    pub fn turning(&self) -> bool {
        self.turned < self.frames
    }

    /// The frame was drawn, its render-thread `times` and `total` time; `settled`: the
    /// forest plan drawn is the one for this camera.
    pub fn drawn(&mut self, moving: bool, times: FrameTimes, total: Duration, settled: bool) {
        let ms = |d: Duration| d.as_secs_f64() * 1000.0;
        let since = self
            .starts
            .len()
            .checked_sub(2)
            .and_then(|k| self.starts.get(k))
            .zip(self.starts.last())
            .filter(|_| moving)
            .map(|(a, b)| {
                let update = self.update.map_or(0.0, ms);
                format!(
                    ", previous frame {:.1} ms (update {update:.1} ms, egui's painting and presenting {:.1} ms)",
                    ms(*b - *a),
                    ms(*b - *a) - update
                )
            })
            .unwrap_or_default();
        eprintln!(
            "orbit frame {}/{} {}: plan {:.1} ms (planner thread{}), upload {:.1} ms ({} instances), submit {:.1} ms, gpu {:.1} ms, render {:.1} ms{since}",
            self.turned,
            self.frames,
            if moving { "moving" } else { "resting" },
            ms(times.plan),
            if times.plan.is_zero() {
                ", none arrived"
            } else {
                ""
            },
            ms(times.upload),
            times.uploaded,
            ms(times.submit),
            ms(times.gpu),
            ms(total),
        );
        if moving || self.finished() {
            return;
        }
        if let Some((rest_start, done)) = &mut self.rest
            && settled
        {
            *done = true;
            let turning = match (self.starts.first(), self.starts.last()) {
                (Some(a), Some(b)) if self.starts.len() > 1 => {
                    (self.starts.len() - 1) as f64 / b.duration_since(*a).as_secs_f64()
                }
                _ => 0.0,
            };
            // Between the first moving frame's start and the first resting frame's: the
            // moving frames but the last.
            let cpu = match self.cpu {
                (Some(a), Some(b)) if self.starts.len() > 1 => format!(
                    ", {:.0} ms of CPU per moving frame (this process, every thread)",
                    ms(b.saturating_sub(a)) / self.starts.len() as f64
                ),
                _ => String::new(),
            };
            eprintln!(
                "orbit: {:.1} frames/s while turning ({} frames){cpu}, resting frame with its final plan {:.0} ms after the turn",
                turning,
                self.starts.len(),
                ms(rest_start.elapsed())
            );
        }
    }
}
