//! The render thread: progressive refinement off the UI thread.
//!
//! The window hands each new scene to [`RenderService::submit`] and never waits. The thread
//! keeps only the newest request (a mailbox, not a queue). A newer request cancels a full
//! frame in flight (the engine's [`Control::cancel`]) but lets a preview finish: inputs come
//! faster than previews render, and cancelling them would show nothing while the user drags.
//! Each request is answered with a
//! reduced-resolution **preview** first (sized so that it takes about
//! [`PREVIEW_BUDGET_MS`](volux_app::preview::PREVIEW_BUDGET_MS)), then, once the user stops
//! interacting, the **full** frame with the scene's own integrator (for adaptive integration,
//! the error-controlled one): the application layer's preview policy
//! ([`volux_app::preview`]). Renderers come from the application layer's
//! [`RendererFactory`] and are kept per method between requests, so their caches
//! (macrocells, gradients, PT's kept set and projection, the tet ray caster's hierarchy)
//! survive camera and TF changes.
//!
//! A bricked volume (an OME-Zarr store rendered out of core) is refined by level instead
//! ([`volux_app::preview::lod_ladder`]): the coarsest level at once (a preview of it while
//! the user drags), then each finer level down to the one its [`Lod`] picks, one frame
//! each, drawn by the factory's renderer of that level (the GPU's brick pool on the GPU
//! backend); a newer request cancels the level in flight, as it cancels a full frame.
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use volux_core::Image;
use volux_render::bricked::{BrickedVolume, Lod};
use volux_render::engine::{FrameStats, Renderer};
use volux_render::scene::{Scene, Volume};
use volux_render::tiles::Control;
use volux_render::RenderError;

use crate::backend::{Backend, Device};
use crate::progressive::{self, LevelShown};
use volux_app::preview::{lod_ladder, preview_method, PreviewPolicy};
use volux_app::RendererFactory;

/// A volume with an identity, so that renderers built for it are reused.
#[derive(Clone, Debug)]
pub struct VolumeRef {
    /// Distinct for every volume the window loads (or derives, like a tetrahedral split).
    pub id: u64,
    /// The data.
    pub volume: Volume,
}

/// What the window asks for.
struct Request {
    volume: VolumeRef,
    scene: Scene,
    interacting: bool,
    generation: u64,
    submitted: Instant,
    cancel: Arc<AtomicBool>,
}

/// A frame the thread finished.
#[derive(Clone, Debug)]
pub struct FinishedFrame {
    /// The picture.
    pub image: Image,
    /// The picture over [`FinishedFrame::background`] as 8-bit sRGB RGBA, ready for the screen
    /// (converted on the render thread: the window only uploads it).
    pub display: Vec<u8>,
    /// The background it was composited over.
    pub background: [f32; 3],
    /// The engine's figures of the frame.
    pub stats: FrameStats,
    /// The request it answers ([`RenderService::submit`]'s number).
    pub generation: u64,
    /// Full resolution with the scene's own integrator (`false`: a preview).
    pub full: bool,
    /// The preview's resolution divisor (1 for full frames).
    pub divisor: usize,
    /// From the request's submission to this frame being ready.
    pub latency: Duration,
    /// The scene it shows (at full size).
    pub scene: Scene,
    /// For a bricked volume: the pyramid level drawn and where refinement stops.
    pub level: Option<LevelShown>,
    /// What drew it: the CPU engine or the GPU adapter named.
    pub device: Device,
}

/// What comes back from the thread.
#[derive(Clone, Debug)]
pub enum Event {
    /// A frame.
    Frame(Box<FinishedFrame>),
    /// The request failed; the message is for the user.
    Failed {
        /// The request.
        generation: u64,
        /// Why.
        message: String,
    },
}

/// The newest request, shared by the window and the thread.
#[derive(Default)]
struct Mailbox {
    slot: Mutex<Option<Request>>,
    background: Mutex<[f32; 3]>,
    ready: Condvar,
    closed: AtomicBool,
    /// The thread is rendering a full frame (which a newer request cancels).
    full_in_flight: AtomicBool,
}

/// The render thread, its mailbox and the frames it sends back.
pub struct RenderService {
    mailbox: Arc<Mailbox>,
    events: Receiver<Event>,
    in_flight: Mutex<Arc<AtomicBool>>,
    generation: u64,
    thread: Option<JoinHandle<()>>,
}

impl RenderService {
    /// Starts the thread rendering on the CPU; `wake` is called after each event (a window
    /// requests a repaint).
    pub fn start(wake: impl Fn() + Send + 'static) -> Self {
        Self::start_on(wake, Backend::Cpu)
    }

    /// Starts the thread rendering on `backend` ([`crate::backend`]).
    pub fn start_on(wake: impl Fn() + Send + 'static, backend: Backend) -> Self {
        let mailbox = Arc::new(Mailbox::default());
        let (tx, events) = channel();
        let worker = Worker {
            mailbox: mailbox.clone(),
            tx,
            wake: Box::new(wake),
            renderers: HashMap::new(),
            factory: RendererFactory::new(backend, crate::backend::gpu_device()),
            previews: PreviewPolicy::default(),
            previewed: None,
        };
        let thread = std::thread::Builder::new()
            .name("volux-render".into())
            .spawn(move || worker.run())
            .expect("the render thread starts");
        Self {
            mailbox,
            events,
            in_flight: Mutex::new(Arc::new(AtomicBool::new(false))),
            generation: 0,
            thread: Some(thread),
        }
    }

    /// Asks for `scene` of `volume`: cancels what is rendering, replaces what waits, and
    /// returns at once with the request's number. `interacting`: the user is still dragging,
    /// so only a preview is wanted.
    pub fn submit(&mut self, volume: &VolumeRef, scene: &Scene, interacting: bool) -> u64 {
        self.generation += 1;
        let cancel = Arc::new(AtomicBool::new(false));
        let previous = std::mem::replace(&mut *lock(&self.in_flight), cancel.clone());
        if self.mailbox.full_in_flight.load(Ordering::SeqCst) {
            previous.store(true, Ordering::SeqCst);
        }
        let request = Request {
            volume: volume.clone(),
            scene: scene.clone(),
            interacting,
            generation: self.generation,
            submitted: Instant::now(),
            cancel,
        };
        *lock(&self.mailbox.slot) = Some(request);
        self.mailbox.ready.notify_one();
        self.generation
    }

    /// The colour frames are composited over for the screen (from the next frame on).
    pub fn set_background(&self, background: [f32; 3]) {
        *lock(&self.mailbox.background) = background;
    }

    /// The number of the newest request.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Events that arrived since the last call, oldest first.
    pub fn poll(&self) -> Vec<Event> {
        self.events.try_iter().collect()
    }

    /// Waits up to `timeout` for the next event (tests and benchmarks; a window polls).
    pub fn wait(&self, timeout: Duration) -> Option<Event> {
        self.events.recv_timeout(timeout).ok()
    }
}

impl Drop for RenderService {
    fn drop(&mut self) {
        lock(&self.in_flight).store(true, Ordering::Relaxed);
        self.mailbox.closed.store(true, Ordering::Relaxed);
        self.mailbox.ready.notify_one();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// A poisoned lock only means another thread panicked while holding it; the data (a
/// request slot, a flag) is still whole.
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// A kept renderer's volume, method name and whether it draws on the GPU.
/// A kept renderer's key: the volume, the method, whether on the GPU, and for a bricked
/// volume the level it draws.
type RendererKey = (u64, &'static str, bool, Option<usize>);

/// The thread's side.
struct Worker {
    mailbox: Arc<Mailbox>,
    tx: Sender<Event>,
    wake: Box<dyn Fn() + Send>,
    /// The renderers kept, by volume, method and whether on the GPU, with what they draw on.
    renderers: HashMap<RendererKey, (Box<dyn Renderer>, Device)>,
    factory: RendererFactory,
    /// Sizes previews from the last one's cost.
    previews: PreviewPolicy,
    /// The last scene previewed: when the same scene comes back without interaction (the
    /// drag ended), only the full frame is rendered.
    previewed: Option<(u64, Scene)>,
}

impl Worker {
    fn run(mut self) {
        while let Some(request) = self.next_request() {
            self.serve(request);
        }
    }

    /// Blocks until a request arrives (`None`: the service was dropped).
    fn next_request(&self) -> Option<Request> {
        let mut slot = lock(&self.mailbox.slot);
        loop {
            if self.mailbox.closed.load(Ordering::Relaxed) {
                return None;
            }
            if let Some(r) = slot.take() {
                return Some(r);
            }
            slot = self
                .mailbox
                .ready
                .wait(slot)
                .unwrap_or_else(|e| e.into_inner());
        }
    }

    fn newer_waiting(&self) -> bool {
        lock(&self.mailbox.slot).is_some()
    }

    fn serve(&mut self, request: Request) {
        if let Volume::Bricked(b, lod) = &request.volume.volume {
            let (b, lod) = (b.clone(), *lod);
            return self.serve_bricked(&request, &b, lod);
        }
        let divisor = self.previews.divisor(&request.scene);
        let seen = self.previewed.as_ref() == Some(&(request.volume.id, request.scene.clone()));
        if !seen || request.interacting || divisor == 1 {
            match self.render(&request, divisor) {
                Ok(()) => {}
                Err(RenderError::Cancelled) => return,
                Err(e) => return self.fail(&request, e),
            }
            self.previewed = Some((request.volume.id, request.scene.clone()));
        }
        // Flag the full frame before looking for newer requests, so that a request arriving
        // in between either is seen here or cancels the frame.
        self.mailbox.full_in_flight.store(true, Ordering::SeqCst);
        if request.interacting || divisor == 1 || self.newer_waiting() {
            self.mailbox.full_in_flight.store(false, Ordering::SeqCst);
            return;
        }
        let result = self.render(&request, 1);
        self.mailbox.full_in_flight.store(false, Ordering::SeqCst);
        match result {
            Ok(()) | Err(RenderError::Cancelled) => {}
            Err(e) => self.fail(&request, e),
        }
    }

    /// Progressive LOD: the coarsest level (a preview of it while interacting), then each
    /// finer level down to the target, each a frame; a newer request stops the walk (and
    /// cancels the level in flight, except the first, which shows something at once).
    fn serve_bricked(&mut self, request: &Request, volume: &Arc<BrickedVolume>, lod: Lod) {
        let ladder = lod_ladder(volume, lod, &request.scene);
        let target = ladder.last().copied().unwrap_or(0);
        let seen = self.previewed.as_ref() == Some(&(request.volume.id, request.scene.clone()));
        for (i, &level) in ladder.iter().enumerate() {
            let last = i + 1 == ladder.len();
            if i == 0 && seen && !last && !request.interacting {
                // The drag's last preview already showed the coarsest level.
                continue;
            }
            if i > 0 {
                self.mailbox.full_in_flight.store(true, Ordering::SeqCst);
                if self.newer_waiting() {
                    break;
                }
            }
            let divisor = if request.interacting {
                self.previews.divisor(&request.scene)
            } else {
                1
            };
            let shown = progressive::level_shown(volume, level, target);
            let result = self.render_bricked_level(request, volume, shown, divisor);
            self.mailbox.full_in_flight.store(false, Ordering::SeqCst);
            match result {
                Ok(()) => {}
                Err(RenderError::Cancelled) => return,
                Err(e) => return self.fail(request, e),
            }
            if i == 0 {
                self.previewed = Some((request.volume.id, request.scene.clone()));
            }
            if request.interacting {
                return;
            }
        }
    }

    /// Renders one level of a bricked volume and sends the frame (full when it is the
    /// target level at full size with the scene's own method; the levels on the way use the
    /// preview's fixed-step integrator).
    fn render_bricked_level(
        &mut self,
        request: &Request,
        volume: &Arc<BrickedVolume>,
        shown: LevelShown,
        divisor: usize,
    ) -> Result<(), RenderError> {
        let full = divisor == 1 && shown.is_final();
        let level = Volume::Bricked(volume.clone(), Lod::Level(shown.level));
        self.render_volume(request, &level, divisor, full, Some(shown))
    }

    fn fail(&self, request: &Request, e: RenderError) {
        let _ = self.tx.send(Event::Failed {
            generation: request.generation,
            message: crate::phrase::phrase(&e),
        });
        (self.wake)();
    }

    /// Renders the request at `1 / divisor` (a preview with a cheap integrator) or in full,
    /// and sends the frame.
    fn render(&mut self, request: &Request, divisor: usize) -> Result<(), RenderError> {
        let volume = request.volume.volume.clone();
        self.render_volume(request, &volume, divisor, divisor == 1, None)
    }

    /// Renders `volume` (the request's, or one level of it) for the request at
    /// `1 / divisor` (a preview with the preview's method unless `full`), with a renderer
    /// from the factory kept for the next frames, and sends the frame.
    fn render_volume(
        &mut self,
        request: &Request,
        volume: &Volume,
        divisor: usize,
        full: bool,
        level: Option<LevelShown>,
    ) -> Result<(), RenderError> {
        let mut scene = request.scene.clone();
        if !full {
            scene.method = preview_method(&scene.method);
        }
        let resolved = scene.method.resolve(volume)?;
        let mut drawn = scene.clone();
        drawn.method = resolved;
        let on_gpu = self.factory.place(volume, &drawn)?.on_gpu;
        let key = (
            request.volume.id,
            resolved.name(),
            on_gpu,
            level.map(|l| l.level),
        );
        if !self.renderers.contains_key(&key) {
            self.renderers
                .retain(|(id, ..), _| *id == request.volume.id);
            let made = self.factory.make(volume, &resolved, on_gpu)?;
            self.renderers.insert(key, made);
        }
        let Some((renderer, device)) = self.renderers.get_mut(&key) else {
            return Err(RenderError::Internal("no renderer".into()));
        };
        let device = device.clone();
        let control = Control {
            cancel: Some(request.cancel.clone()),
            progress: None,
        };
        let frame = if divisor > 1 {
            renderer.render_preview(&scene, &control, divisor)?
        } else {
            renderer.render(&scene, &control)?
        };
        if divisor > 1 {
            self.previews.measured(&frame);
        }
        self.send(request, frame, (full, divisor), level, device);
        Ok(())
    }

    /// Sends a finished frame to the window.
    fn send(
        &self,
        request: &Request,
        frame: volux_render::engine::Frame,
        (full, divisor): (bool, usize),
        level: Option<LevelShown>,
        device: Device,
    ) {
        let background = *lock(&self.mailbox.background);
        let rendered = FinishedFrame {
            display: frame.image.to_srgba8(background),
            background,
            image: frame.image,
            stats: frame.stats,
            generation: request.generation,
            full,
            divisor,
            latency: request.submitted.elapsed(),
            scene: request.scene.clone(),
            level,
            device,
        };
        let _ = self.tx.send(Event::Frame(Box::new(rendered)));
        (self.wake)();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use volux_core::{synth, CameraSpec};
    use volux_render::integrate::segment::SegmentRule;
    use volux_render::scene::Method;

    fn volume() -> VolumeRef {
        VolumeRef {
            id: 1,
            volume: Volume::from(synth::marschner_lobb(24).unwrap()),
        }
    }

    fn scene(v: &VolumeRef, w: usize) -> Scene {
        let camera = CameraSpec::default().resolve(&v.volume.bounds()).unwrap();
        Scene::new(camera, w, w, v.volume.preset_tf("auto").unwrap())
    }

    fn next_frame(s: &RenderService) -> FinishedFrame {
        match s.wait(Duration::from_secs(60)).expect("a frame") {
            Event::Frame(f) => *f,
            Event::Failed { message, .. } => panic!("{message}"),
        }
    }

    /// A request gets a preview, then the full frame, equal to a one-off render.
    #[test]
    fn preview_then_full_frame() {
        let v = volume();
        let s = scene(&v, 64);
        let mut service = RenderService::start(|| {});
        let g = service.submit(&v, &s, false);
        let preview = next_frame(&service);
        assert!(!preview.full && preview.generation == g);
        assert_eq!(preview.image.width(), 64 / preview.divisor);
        let full = next_frame(&service);
        assert!(full.full && full.image.width() == 64);
        let once = volux_render::engine::render_once(&v.volume, &s, &Control::default()).unwrap();
        assert_eq!(full.image, once.image);
    }

    /// While interacting only previews come; a newer request supersedes older ones.
    #[test]
    fn interaction_gets_previews_and_newest_wins() {
        let v = volume();
        let mut service = RenderService::start(|| {});
        for w in [40, 48, 56] {
            service.submit(&v, &scene(&v, w), true);
        }
        let last = service.submit(&v, &scene(&v, 64), false);
        let mut frames = vec![];
        while let Some(Event::Frame(f)) = service.wait(Duration::from_secs(5)) {
            let done = f.full;
            frames.push(*f);
            if done {
                break;
            }
        }
        let full = frames.last().unwrap();
        assert!(full.full && full.generation == last);
        assert!(frames.iter().all(|f| f.full == (f.divisor == 1)));
        assert!(frames.iter().filter(|f| f.full).count() == 1);
    }

    /// A failing request is reported, and the thread serves the next one.
    #[test]
    fn errors_are_reported_and_the_thread_lives_on() {
        let v = volume();
        let mut service = RenderService::start(|| {});
        let mut bad = scene(&v, 32);
        bad.method = Method::TetRaycast(SegmentRule::Psi);
        service.submit(&v, &bad, false);
        match service.wait(Duration::from_secs(10)) {
            Some(Event::Failed { message, .. }) => assert!(message.contains("tet"), "{message}"),
            other => panic!("expected a failure, got {other:?}"),
        }
        service.submit(&v, &scene(&v, 32), false);
        assert!(!next_frame(&service).full);
    }
}
