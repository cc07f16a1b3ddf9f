//! Running a scene: frames, the truth of each, and the events of faults and drift, frame by frame.

use super::*;

/// The truth behind one simulated frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// Scene time at the start of the frame, s.
    pub time: f64,
    /// Touches as the fabric feels them (effective pressure after dynamics; touches still
    /// relaxing after they lifted are included while their effect lasts).
    pub touches: Vec<Touch>,
}

/// How much of the acquisition to simulate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Detail {
    /// Every sample through the real scan engine (slow, exact).
    Samples,
    /// Whole frames with the same statistics ([`SimFrontend::fast_frame`]).
    Frames,
}

/// A scene running: a sensor and a clock.
#[derive(Debug)]
pub struct Run {
    scene: Scene,
    config: ScanConfig,
    frontend: SimFrontend,
    scanner: Scanner,
    pub(super) seq: u32,
    frame_period: f64,
    /// Per touch event: effective pressure, peak pressure seen, last position.
    state: Vec<(f64, f64, [f64; 2])>,
    /// Touches added live (a pointer pressing the sheet in the viewer), on top of the
    /// scene's, without dynamics.
    extra: Vec<Touch>,
    /// Scene time at frame `seq_base` (the clock restarts its count when the frame period
    /// changes), s.
    clock_base: f64,
    seq_base: u32,
    /// While held, the scene's own touches wait; their timeline starts at release.
    held: bool,
    released_at: f64,
}

impl Scene {
    /// Each electrode's offset along the outline, m: `[movement]`'s rms times a normal draw
    /// from `moves` (the scene's seed, forked once, as every simulation of the scene draws
    /// them).
    fn offsets_from(&self, moves: &mut Rng) -> Vec<f64> {
        (0..self.sheet.physical.electrodes.count)
            .map(|_| self.movement.rms * moves.normal())
            .collect()
    }

    /// The electrodes' offsets along the outline as the scene's seed draws them, m (zeros
    /// without `[movement]`): the sheet every simulation of the scene measures.
    #[must_use]
    pub fn electrode_offsets(&self) -> Vec<f64> {
        self.offsets_from(&mut Rng::new(self.seed).fork())
    }

    /// The pairs of electrodes `[[fault]]` shorts together (0-based).
    #[must_use]
    pub fn shorts(&self) -> Vec<(usize, usize)> {
        (self.faults.iter())
            .filter(|f| f.kind == FaultKind::Shorted)
            .filter_map(|f| f.with.map(|w| (usize::from(f.electrode), usize::from(w))))
            .collect()
    }
}

impl Run {
    /// Builds the sheet (with electrode movement drawn from the seed) and the front end in
    /// one measurement set (junction potentials and conductance drawn from the seed).
    ///
    /// # Errors
    /// [`SceneError`] if the sheet cannot be built (e.g. electrodes overlapping at the
    /// chosen resolution).
    pub fn new(scene: &Scene) -> Result<Self, SceneError> {
        let config = scene.board_config()?;
        let mut rng = Rng::new(scene.seed);
        let mut moves = rng.fork();
        let offsets = scene.offsets_from(&mut moves);
        scene.check_touches_resolved()?;
        let sheet = SimulatedSheet::with_shorts(&scene.sheet, &offsets, &scene.shorts())?;
        let mut frontend = SimFrontend::new(Arc::new(sheet), scene.frontend, rng.next_u64())?;
        // A scene is one measurement set: its junction potentials and conductance.
        let set = scene.frontend.sets.draw(
            usize::from(scene.sheet.physical.electrodes.count),
            &mut moves,
        );
        frontend.set_state(&set)?;
        for f in &scene.faults {
            let p = match f.kind {
                FaultKind::Disconnected => 1.0,
                FaultKind::Intermittent => f.probability.unwrap_or(0.0),
                FaultKind::Shorted => continue,
            };
            frontend.set_open(f.electrode, p)?;
        }
        let scanner = Scanner::new(config, &mut frontend)?;
        let frame_period = 1.0 / f64::from(config.frame_rate_hz());
        let state = scene
            .touches
            .iter()
            .map(|t| (0.0, 0.0, t.position))
            .collect();
        Ok(Self {
            scene: scene.clone(),
            config,
            frontend,
            scanner,
            seq: 0,
            frame_period,
            state,
            extra: Vec::new(),
            clock_base: 0.0,
            seq_base: 0,
            held: false,
            released_at: 0.0,
        })
    }

    /// Scene time of the next frame, s.
    fn clock(&self) -> f64 {
        self.clock_base + f64::from(self.seq - self.seq_base) * self.frame_period
    }

    /// Holds the scene's own touches back (`true`) until released (`false`); their timeline
    /// then starts at the release, so a live display can take its untouched reference first.
    pub fn hold_scene(&mut self, held: bool) {
        if self.held && !held {
            self.released_at = self.clock();
        }
        self.held = held;
    }

    /// Scans with `config` from the next frame on (another protocol, say), as a device
    /// obeying `Configure` would.
    ///
    /// # Errors
    /// [`SceneError`] for a configuration the sheet cannot scan.
    pub fn set_config(&mut self, config: ScanConfig) -> Result<(), SceneError> {
        let scanner = Scanner::new(config, &mut self.frontend)?;
        self.scanner = scanner;
        self.config = config;
        self.clock_base = self.clock();
        self.seq_base = self.seq;
        self.frame_period = 1.0 / f64::from(config.frame_rate_hz());
        Ok(())
    }

    /// Touches pressed live on top of the scene's own from the next frame on (empty: none).
    pub fn set_extra_touches(&mut self, touches: Vec<Touch>) {
        self.extra = touches;
    }

    /// The scene this run plays.
    #[must_use]
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The scan configuration.
    #[must_use]
    pub fn config(&self) -> &ScanConfig {
        &self.config
    }

    /// The sensor.
    #[must_use]
    pub fn frontend(&self) -> &SimFrontend {
        &self.frontend
    }

    /// Seconds per frame.
    #[must_use]
    pub fn frame_period(&self) -> f64 {
        self.frame_period
    }

    /// Advances the touch dynamics to time `t` (one frame period later than the last call).
    fn touches_at(&mut self, t: f64) -> Vec<Touch> {
        let d = self.scene.dynamics;
        let dt = self.frame_period;
        let scheduled = self.scene.scheduled(t);
        let mut out = Vec::new();
        for (ev, (state, target)) in self
            .scene
            .touches
            .iter()
            .zip(self.state.iter_mut().zip(scheduled))
        {
            let (p, peak, pos) = state;
            let goal = target.map_or(0.0, |t| t.pressure);
            if let Some(t) = target {
                *pos = t.position;
            }
            let tau = if goal >= *p { d.load_s } else { d.unload_s };
            *p = if tau > 0.0 {
                goal + (*p - goal) * (-dt / tau).exp()
            } else {
                goal
            };
            *peak = if goal > 0.0 {
                peak.max(*p)
            } else {
                *peak * (-dt / d.unload_s.max(1e-9)).exp()
            };
            // Hysteresis: on the way down the fabric feels a little of the peak it saw.
            let felt = *p
                + if goal < *p {
                    d.hysteresis * (*peak - *p)
                } else {
                    0.0
                };
            if felt > 1e-3 * ev.pressure.max(1.0) {
                out.push(Touch {
                    position: *pos,
                    radius: ev.radius,
                    pressure: felt,
                    footprint: ev.footprint,
                });
            }
        }
        out
    }

    /// Simulates the next frame and says what was really on the sheet.
    ///
    /// # Errors
    /// [`SceneError`] if the simulation fails.
    pub fn next_frame(&mut self, detail: Detail) -> Result<(Frame, Truth), SceneError> {
        let t = self.clock();
        let mut touches = if self.held {
            Vec::new()
        } else {
            self.touches_at(t - self.released_at)
        };
        touches.extend(self.extra.iter().copied());
        self.frontend.set_touches(&touches)?;
        if let Some(d) = self.scene.drift {
            let c = (1.0 + d.per_kelvin * d.kelvin_per_minute * t / 60.0).max(1e-3);
            self.frontend.set_conductance_scale(c)?;
        }
        let k = self.scanner.frame_len();
        let (voltages, report) = match detail {
            Detail::Frames => self.frontend.fast_frame_with_report(&self.config)?,
            Detail::Samples => {
                let mut v = vec![0.0f32; k];
                let mut burst = vec![0u16; usize::from(self.config.samples_per_step)];
                let r = self.scanner.scan(&mut self.frontend, &mut burst, &mut v)?;
                (v, r)
            }
        };
        // The board's microsecond counter: 32 bits that wrap every 71.6 minutes (readers
        // take differences with `Micros::since`), not a value that stops at the top.
        let micros = Micros(((t * 1e6) as u64 & u64::from(u32::MAX)) as u32);
        let frame = Frame::from_scan(self.seq, micros, self.config, &report, 0, &voltages)?;
        self.seq += 1;
        Ok((frame, Truth { time: t, touches }))
    }
}
