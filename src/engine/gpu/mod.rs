//! The `gpu` engine: WGSL kernels on wgpu.

pub mod compose;
pub mod layout;
pub mod paths;
pub mod shaders;
pub mod validate;

use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use anyhow::{anyhow, bail, Context as _};
use rayon::prelude::*;
use wgpu::util::DeviceExt;

use self::layout::{GpuDesign, GpuOutcome, GpuParticle, GpuPhysics};
use self::paths::KernelPaths;
use super::cpu::{kernel_design, kernel_physics, CpuEngine, Precision};
use super::kernel::{init_particle, STATE_LOST, STATE_RESTING};
use super::{cpu_only_effects, finish_outcome, BatchEvaluator, Context, Evaluation, FlightRecord, ParticleEngine, Run};
use crate::model::outcome::{from_counts, ParticleEnd, ParticleState, SimOutcome};
use crate::model::{prepare, Design, Invalid, Prepared, Scenario};

/// Which adapters the engine may take.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AdapterChoice {
    /// Any Vulkan adapter, software (Mesa lavapipe) included: `--engine gpu`, CI conformance.
    Any,
    /// Only a hardware GPU: `--engine auto`.
    HardwareOnly,
}

/// Threads per workgroup of every kernel (WGSL `WG`, kernel.rs `WG`).
const WORKGROUP_SIZE: u64 = super::kernel::WG as u64;

/// A batch that has not finished after this long counts as a GPU failure.
const TIMEOUT: Duration = Duration::from_secs(120);

pub struct GpuEngine {
    device: wgpu::Device,
    queue: wgpu::Queue,
    module: wgpu::ShaderModule,
    pipeline_layout: wgpu::PipelineLayout,
    /// The simulation pipelines of each variant of the kernel's optional paths used so far
    /// (built on first use; see `paths.rs`).
    simulators: Mutex<HashMap<KernelPaths, Arc<Simulators>>>,
    /// Physical mode's per-design reduction (`reduce_designs`), the same for every variant.
    reduce_pipeline: wgpu::ComputePipeline,
    bind_layout: wgpu::BindGroupLayout,
    info: wgpu::AdapterInfo,
    limits: wgpu::Limits,
    /// Errors the device reported outside an error scope (e.g. device loss).
    uncaptured: Arc<Mutex<Option<String>>>,
    /// Kernel dispatches submitted so far (see [`GpuEngine::dispatches`]).
    dispatches: AtomicUsize,
    /// Designs run on the `cpu` engine because their effects are not in the kernel.
    cpu_only_designs: AtomicUsize,
    /// Whether the warning about such designs has been printed (once per engine).
    warned_cpu_only: AtomicBool,
    /// The most designs `evaluate_groups` prepares and submits at once, so that the host
    /// prepares the next slice while the device runs this one; 0: the whole batch at once.
    slice_designs: AtomicUsize,
}

/// The simulation pipelines of one variant of the kernel's optional paths.
struct Simulators {
    /// Listing mode: one workgroup per design, bounce by bounce (`simulate`).
    simulate: wgpu::ComputePipeline,
    /// Physical mode: one thread per particle (`simulate_particles`), then `reduce_designs`.
    simulate_particles: wgpu::ComputePipeline,
}

/// A compute pipeline of `module`'s entry point `name`, with the path switches `paths`.
fn compute_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    name: &str,
    paths: KernelPaths,
) -> wgpu::ComputePipeline {
    let constants = paths.constants();
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(name),
        layout: Some(layout),
        module,
        entry_point: Some(name),
        compilation_options: wgpu::PipelineCompilationOptions { constants: &constants, ..Default::default() },
        cache: None,
    })
}

/// What one simulated design returns: its outcome and, when asked for, every particle.
type DesignRun = (SimOutcome, Option<Vec<ParticleEnd>>);

/// What one dispatch of a chunk of designs returns.
struct ChunkResult {
    outcomes: Vec<GpuOutcome>,
    histogram: Vec<u32>,
    particles: Option<Vec<GpuParticle>>,
}

/// A dispatch submitted and not yet read back ([`GpuEngine::submit_chunk`],
/// [`GpuEngine::finish_chunk`]).
struct PendingChunk {
    readback: wgpu::Buffer,
    index: wgpu::SubmissionIndex,
    /// Answers once the readback buffer is mapped (or failed to be).
    mapped: std::sync::mpsc::Receiver<Result<(), wgpu::BufferAsyncError>>,
    outcome_size: u64,
    hist_size: u64,
    want_particles: bool,
    designs: usize,
    particles: usize,
    t_submit: std::time::Instant,
}

impl GpuEngine {
    pub fn new(choice: AdapterChoice) -> anyhow::Result<Self> {
        let slice_designs = slice_designs_from_env()?;
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
        let hardware = |a: &wgpu::Adapter| a.get_info().device_type != wgpu::DeviceType::Cpu;
        let adapter = match choice {
            AdapterChoice::HardwareOnly => adapters.into_iter().find(hardware),
            AdapterChoice::Any => {
                let mut all = adapters;
                all.sort_by_key(|a| !hardware(a)); // hardware first
                all.into_iter().next()
            }
        };
        let adapter = adapter.ok_or_else(|| match choice {
            AdapterChoice::Any => anyhow!(
                "no Vulkan adapter found: install a GPU driver, or Mesa's software Vulkan \
                 (`apt-get install mesa-vulkan-drivers libvulkan1`), or use the cpu engine"
            ),
            AdapterChoice::HardwareOnly => anyhow!("no hardware GPU adapter"),
        })?;
        let info = adapter.get_info();
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("sawtooth"),
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .with_context(|| format!("cannot open GPU device {}", info.name))?;
        let uncaptured = Arc::new(Mutex::new(None));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            *sink.lock().unwrap() = Some(e.to_string());
        }));
        let source = shaders::compose("particles.wgsl").map_err(anyhow::Error::msg)?;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("particles.wgsl"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let storage = |binding: u32, read_only: bool| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let bind_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("particles"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                storage(1, true),
                storage(2, false),
                storage(3, false),
                storage(4, false),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("particles"),
            bind_group_layouts: &[Some(&bind_layout)],
            immediate_size: 0,
        });
        // the general kernel now, so that a pipeline the driver rejects fails here
        let general = Simulators {
            simulate: compute_pipeline(&device, &pipeline_layout, &module, "simulate", KernelPaths::ALL),
            simulate_particles: compute_pipeline(
                &device,
                &pipeline_layout,
                &module,
                "simulate_particles",
                KernelPaths::ALL,
            ),
        };
        let reduce_pipeline = compute_pipeline(&device, &pipeline_layout, &module, "reduce_designs", KernelPaths::ALL);
        if let Some(e) = uncaptured.lock().unwrap().take() {
            bail!("GPU pipeline creation failed: {e}");
        }
        Ok(GpuEngine {
            device,
            queue,
            module,
            pipeline_layout,
            simulators: Mutex::new(HashMap::from([(KernelPaths::ALL, Arc::new(general))])),
            reduce_pipeline,
            bind_layout,
            info,
            limits,
            uncaptured,
            dispatches: AtomicUsize::new(0),
            cpu_only_designs: AtomicUsize::new(0),
            warned_cpu_only: AtomicBool::new(false),
            slice_designs: AtomicUsize::new(slice_designs),
        })
    }

    /// "name (backend, device type)" for logs and run manifests, and the slices when a batch
    /// is split ([`GpuEngine::set_slice_designs`]).
    pub fn describe(&self) -> String {
        let slices = match self.slice_designs() {
            0 => String::new(),
            n => format!("; batches in slices of {n} designs, the next prepared while one runs"),
        };
        format!(
            "{} ({:?}, {:?}, driver {}){slices}",
            self.info.name, self.info.backend, self.info.device_type, self.info.driver_info
        )
    }

    /// Split each batch of `evaluate`/`evaluate_groups` into slices of at most `designs`
    /// designs (0: the whole batch at once, the default), so that the host prepares a slice
    /// (fill area, launch points, records) while the device runs the one before. The results
    /// are those of the whole batch at once, except where a slice's records need fewer of
    /// the kernel's optional paths than the whole batch's (`paths.rs`: then the driver's f32
    /// rounding may differ). On lavapipe, whose device is the host's own cores, slices cost
    /// time (BENCHMARKS.md); on a hardware GPU whether they pay is measured by
    /// `scripts/gpu-table.sh`. The CLI reads `SAWTOOTH_GPU_SLICE_DESIGNS`.
    pub fn set_slice_designs(&self, designs: usize) {
        self.slice_designs.store(designs, Ordering::Relaxed);
    }

    /// See [`GpuEngine::set_slice_designs`].
    pub fn slice_designs(&self) -> usize {
        self.slice_designs.load(Ordering::Relaxed)
    }

    pub fn is_hardware(&self) -> bool {
        self.info.device_type != wgpu::DeviceType::Cpu
    }

    /// Kernel dispatches this engine has submitted (one per chunk of designs), for tests and
    /// profiling: a calibration's one-design groups should cost one dispatch per call.
    pub fn dispatches(&self) -> usize {
        self.dispatches.load(Ordering::Relaxed)
    }

    /// Designs this engine handed to the `cpu` engine because an effect they switch on is not
    /// in the kernel (`cpu_only_effects`).
    pub fn cpu_only_designs(&self) -> usize {
        self.cpu_only_designs.load(Ordering::Relaxed)
    }

    /// The simulation pipelines for `paths`, built on first use (inside the caller's error
    /// scope: a variant the driver rejects fails that dispatch, which then runs on the cpu
    /// engine).
    fn simulators(&self, paths: KernelPaths) -> Arc<Simulators> {
        let mut cache = self.simulators.lock().unwrap();
        cache
            .entry(paths)
            .or_insert_with(|| {
                let build =
                    |name: &str| compute_pipeline(&self.device, &self.pipeline_layout, &self.module, name, paths);
                Arc::new(Simulators { simulate: build("simulate"), simulate_particles: build("simulate_particles") })
            })
            .clone()
    }

    /// Designs per dispatch: workgroups per dimension and storage binding size respected.
    fn chunk_designs(&self, n_particles: u32, teeth: u32) -> usize {
        let per_design_particles = n_particles as u64 * std::mem::size_of::<GpuParticle>() as u64;
        let per_design_hist = teeth as u64 * 4;
        let binding = self.limits.max_storage_buffer_binding_size.min(self.limits.max_buffer_size);
        let by_storage = (binding / per_design_particles.max(per_design_hist).max(1)).max(1);
        (self.limits.max_compute_workgroups_per_dimension as u64).min(by_storage).max(1) as usize
    }

    /// One dispatch, its records returned raw: per design its outcome and `teeth_hist`
    /// histogram bins, and every particle as the kernel left it. For tests of the Rust twins
    /// (tests/gpu_conformance.rs runs `kernel::reduce` on the particles and compares).
    #[doc(hidden)]
    pub fn dispatch_raw(
        &self,
        phys: &GpuPhysics,
        designs: &[GpuDesign],
        particles: &[GpuParticle],
    ) -> anyhow::Result<(Vec<GpuOutcome>, Vec<u32>, Vec<GpuParticle>)> {
        self.dispatch_raw_with(phys, designs, particles, KernelPaths::of(designs, particles))
    }

    /// [`GpuEngine::dispatch_raw`] with the kernel's path switches given instead of taken
    /// from the records (tests/gpu_conformance.rs: switching off the paths no record takes
    /// leaves the particles as the general kernel does, up to the driver's f32 rounding).
    #[doc(hidden)]
    pub fn dispatch_raw_with(
        &self,
        phys: &GpuPhysics,
        designs: &[GpuDesign],
        particles: &[GpuParticle],
        paths: KernelPaths,
    ) -> anyhow::Result<(Vec<GpuOutcome>, Vec<u32>, Vec<GpuParticle>)> {
        let r = self.finish_chunk(self.submit_chunk(phys, designs, particles, true, paths)?)?;
        Ok((r.outcomes, r.histogram, r.particles.unwrap_or_default()))
    }

    /// One dispatch of a chunk of designs, up to its submission: the records uploaded, the
    /// kernels and the copies to the readback buffer submitted, and its mapping requested;
    /// the device works on it while the caller goes on (packing the next chunk, preparing the
    /// next slice) until [`GpuEngine::finish_chunk`]. Validation and out-of-memory errors of
    /// the submission are reported here.
    fn submit_chunk(
        &self,
        phys: &GpuPhysics,
        designs: &[GpuDesign],
        particles: &[GpuParticle],
        want_particles: bool,
        paths: KernelPaths,
    ) -> anyhow::Result<PendingChunk> {
        let dev = &self.device;
        let n = designs.len();
        let scope = dev.push_error_scope(wgpu::ErrorFilter::Validation);
        let oom = dev.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let sim = self.simulators(paths);
        let uniform = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("physics"),
            contents: bytemuck::bytes_of(phys),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let design_buf = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("designs"),
            contents: bytemuck::cast_slice(designs),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let particle_buf = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("particles"),
            contents: bytemuck::cast_slice(particles),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        });
        let outcome_size = (n * std::mem::size_of::<GpuOutcome>()) as u64;
        let outcome_buf = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("outcomes"),
            size: outcome_size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let hist_size = (n * phys.teeth_hist as usize * 4) as u64;
        let hist_buf = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("histogram"),
            size: hist_size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let particle_size = std::mem::size_of_val(particles) as u64;
        let read_size = outcome_size + hist_size + if want_particles { particle_size } else { 0 };
        let readback = dev.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: read_size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind = dev.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("particles"),
            layout: &self.bind_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: design_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: particle_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: outcome_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: hist_buf.as_entire_binding() },
            ],
        });
        let mut enc = dev.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("simulate") });
        enc.clear_buffer(&hist_buf, 0, None);
        if phys.per_particle_rest != 0 {
            // a thread per particle, then (a separate pass: the reduction reads what every
            // particle's thread wrote) a thread per design
            let groups = (particles.len() as u64).div_ceil(WORKGROUP_SIZE);
            let per_dim = self.limits.max_compute_workgroups_per_dimension as u64;
            let (x, y) = (groups.min(per_dim), groups.div_ceil(per_dim));
            {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("simulate_particles"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(&sim.simulate_particles);
                pass.set_bind_group(0, &bind, &[]);
                pass.dispatch_workgroups(x as u32, y as u32, 1);
            }
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("reduce_designs"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.reduce_pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups((n as u64).div_ceil(WORKGROUP_SIZE) as u32, 1, 1);
        } else {
            let mut pass = enc
                .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("simulate"), timestamp_writes: None });
            pass.set_pipeline(&sim.simulate);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(n as u32, 1, 1);
        }
        enc.copy_buffer_to_buffer(&outcome_buf, 0, &readback, 0, outcome_size);
        enc.copy_buffer_to_buffer(&hist_buf, 0, &readback, outcome_size, hist_size);
        if want_particles {
            enc.copy_buffer_to_buffer(&particle_buf, 0, &readback, outcome_size + hist_size, particle_size);
        }
        let t_submit = std::time::Instant::now();
        self.dispatches.fetch_add(1, Ordering::Relaxed);
        let index = self.queue.submit([enc.finish()]);
        if let Some(e) = pollster::block_on(oom.pop()) {
            bail!("GPU out of memory: {e}");
        }
        if let Some(e) = pollster::block_on(scope.pop()) {
            bail!("GPU validation error: {e}");
        }
        let (tx, mapped) = std::sync::mpsc::channel();
        readback.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        Ok(PendingChunk {
            readback,
            index,
            mapped,
            outcome_size,
            hist_size,
            want_particles,
            designs: n,
            particles: particles.len(),
            t_submit,
        })
    }

    /// The rest of a [`GpuEngine::submit_chunk`]: wait for the device, read the records back.
    fn finish_chunk(&self, pending: PendingChunk) -> anyhow::Result<ChunkResult> {
        let PendingChunk { readback, index, mapped, outcome_size, hist_size, want_particles, .. } = pending;
        self.device
            .poll(wgpu::PollType::Wait { submission_index: Some(index), timeout: Some(TIMEOUT) })
            .map_err(|e| anyhow!("GPU batch did not finish: {e}"))?;
        mapped
            .recv_timeout(TIMEOUT)
            .map_err(|_| anyhow!("GPU readback never completed"))?
            .map_err(|e| anyhow!("GPU readback failed: {e}"))?;
        if let Some(e) = self.uncaptured.lock().unwrap().take() {
            bail!("GPU error: {e}");
        }
        let waited = pending.t_submit.elapsed();
        let slice = readback.slice(..);
        let view = slice.get_mapped_range().map_err(|e| anyhow!("GPU readback mapping failed: {e:?}"))?;
        let bytes: &[u8] = &view;
        let (o, rest) = bytes.split_at(outcome_size as usize);
        let (h, p) = rest.split_at(hist_size as usize);
        let result = ChunkResult {
            outcomes: bytemuck::pod_collect_to_vec(o),
            histogram: bytemuck::pod_collect_to_vec(h),
            particles: want_particles.then(|| bytemuck::pod_collect_to_vec(p)),
        };
        drop(view);
        readback.unmap();
        if std::env::var_os("SAWTOOTH_PROFILE").is_some() {
            eprintln!(
                "profile gpu: {} designs, {} particles: submit-to-readback {:.3} ms (kernel + copies)",
                pending.designs,
                pending.particles,
                waited.as_secs_f64() * 1e3,
            );
        }
        Ok(result)
    }

    /// Simulate prepared designs under one context; per design the outcome and (optionally)
    /// every particle. See [`GpuEngine::run_jobs`].
    pub fn run_prepared(&self, ctx: &Context, preps: &[&Prepared], want_particles: bool) -> Vec<DesignRun> {
        let jobs: Vec<(&Context, &Prepared)> = preps.iter().map(|p| (ctx, *p)).collect();
        self.run_jobs(&jobs, want_particles)
    }

    /// Simulate prepared designs, each under its own context; results in the order given.
    ///
    /// Designs whose batch-wide record ([`GpuPhysics`]: g, randomisation schedule and band,
    /// seed, rest rule and threshold, max bounces, particle and tooth counts) is the same run in
    /// one dispatch (split only where adapter limits demand), each design carrying its own
    /// restitution and effect parameters in its [`GpuDesign`] and its own drag in its
    /// particles' k_drag. The key is the f32 record the kernel reads, so designs share a
    /// dispatch exactly when the kernel could not tell their batch-wide physics apart.
    ///
    /// Designs with an effect the kernel lacks (`cpu_only_effects`: sled motion, quadratic
    /// drag, uniform sizes) run on the `cpu` engine at f32 (the kernel's twin), with a warning
    /// printed once per engine: running them on the GPU would silently drop the effect.
    /// (`make_engine_for` refuses `--engine gpu` for such a scenario up front; this covers the
    /// callers whose effects vary per group, e.g. diagnose's candidates.)
    ///
    /// A chunk the GPU fails on is re-run on the `cpu` engine (f32) with a warning, so a
    /// failure loses no work.
    pub fn run_jobs(&self, jobs: &[(&Context, &Prepared)], want_particles: bool) -> Vec<DesignRun> {
        let submitted = self.submit_jobs(jobs, want_particles);
        self.collect_jobs(jobs, submitted)
    }

    /// The first half of [`GpuEngine::run_jobs`]: the designs with a cpu-only effect run, and
    /// the others' dispatches submitted; [`GpuEngine::collect_jobs`] (with the same `jobs`)
    /// waits for them.
    fn submit_jobs(&self, jobs: &[(&Context, &Prepared)], want_particles: bool) -> Submitted {
        let mut out: Vec<Option<DesignRun>> = (0..jobs.len()).map(|_| None).collect();
        let mut batches: Vec<(GpuPhysics, Vec<usize>)> = Vec::new();
        let mut on_cpu: Vec<usize> = Vec::new();
        for (i, (ctx, prep)) in jobs.iter().enumerate() {
            let cpu_only = cpu_only_effects(&ctx.effects);
            if !cpu_only.is_empty() {
                if !self.warned_cpu_only.swap(true, Ordering::Relaxed) {
                    eprintln!(
                        "warning: gpu engine: {}; designs with such an effect run on the cpu engine (f32)",
                        super::in_cpu_engine_only(&cpu_only)
                    );
                }
                on_cpu.push(i);
                continue;
            }
            let key = GpuPhysics::from_kernel(
                &kernel_physics::<f32>(ctx),
                ctx.max_bounces,
                prep.launches.len() as u32,
                0,
                prep.profile.teeth,
            );
            match batches.iter_mut().find(|(k, _)| bytemuck::bytes_of(k) == bytemuck::bytes_of(&key)) {
                Some((_, members)) => members.push(i),
                None => batches.push((key, vec![i])),
            }
        }
        if !on_cpu.is_empty() {
            self.cpu_only_designs.fetch_add(on_cpu.len(), Ordering::Relaxed);
            let redo = run_on_cpu(jobs, &on_cpu, want_particles);
            for (i, r) in on_cpu.into_iter().zip(redo) {
                out[i] = Some(r);
            }
        }
        let mut in_flight: Vec<InFlight> = Vec::new();
        for (key, members) in batches {
            for chunk in members.chunks(self.chunk_designs(key.n_particles, key.teeth_hist)) {
                // a batch the device limits split: one chunk on the device while the next is
                // packed, so no more than two chunks' buffers at once
                if in_flight.len() == 2 {
                    self.read_back(jobs, in_flight.remove(0), &mut out, want_particles);
                }
                let pending = self.submit_batch(key, jobs, chunk, want_particles);
                in_flight.push(InFlight { key, chunk: chunk.to_vec(), pending });
            }
        }
        Submitted { runs: out, in_flight, want_particles }
    }

    /// The second half of [`GpuEngine::run_jobs`]: each dispatch read back and turned into
    /// its designs' runs, in the order of `jobs`.
    fn collect_jobs(&self, jobs: &[(&Context, &Prepared)], submitted: Submitted) -> Vec<DesignRun> {
        let Submitted { runs: mut out, in_flight, want_particles } = submitted;
        for flight in in_flight {
            self.read_back(jobs, flight, &mut out, want_particles);
        }
        out.into_iter().map(|r| r.expect("every design is run")).collect()
    }

    /// One dispatch read back into its designs' places in `out`; one the GPU failed on is
    /// re-run on the `cpu` engine (f32) with a warning.
    fn read_back(
        &self,
        jobs: &[(&Context, &Prepared)],
        flight: InFlight,
        out: &mut [Option<DesignRun>],
        want_particles: bool,
    ) {
        let InFlight { key, chunk, pending } = flight;
        let runs = match pending.and_then(|p| self.finish_chunk(p)) {
            Ok(r) => design_runs(key, jobs, &chunk, &r),
            Err(e) => {
                eprintln!(
                    "warning: GPU failed on a batch of {} designs ({e:#}); re-running it on the cpu engine",
                    chunk.len()
                );
                run_on_cpu(jobs, &chunk, want_particles)
            }
        };
        for (i, r) in chunk.iter().zip(runs) {
            out[*i] = Some(r);
        }
    }

    /// The records of `jobs[chunk]` (which share the batch-wide record `key`) packed and
    /// submitted as one dispatch.
    fn submit_batch(
        &self,
        key: GpuPhysics,
        jobs: &[(&Context, &Prepared)],
        chunk: &[usize],
        want_particles: bool,
    ) -> anyhow::Result<PendingChunk> {
        let n_particles = key.n_particles;
        // The records, on every core: packing a pop-1000 generation's 100 000 particles one
        // design after another was host time the device waited for (issue 16).
        let t_pack = std::time::Instant::now();
        let mut particles = vec![<GpuParticle as bytemuck::Zeroable>::zeroed(); chunk.len() * n_particles as usize];
        let designs: Vec<GpuDesign> = chunk
            .par_iter()
            .zip(particles.par_chunks_mut(n_particles as usize))
            .map(|(&i, slots)| {
                let (ctx, prep) = jobs[i];
                // the design's own physics: restitution and effects into its record, its drag
                // (polydisperse or not) into its particles
                let kp = kernel_physics::<f32>(ctx);
                let kd = kernel_design::<f32>(prep);
                for (j, (slot, l)) in slots.iter_mut().zip(&prep.launches).enumerate() {
                    *slot = GpuParticle::from(&init_particle(&kd, &kp, [l[0] as f32, l[1] as f32], j as u32));
                }
                GpuDesign::new(&kd, &kp)
            })
            .collect();
        if std::env::var_os("SAWTOOTH_PROFILE").is_some() {
            eprintln!(
                "profile gpu: packing {} designs' records {:.3} ms",
                chunk.len(),
                t_pack.elapsed().as_secs_f64() * 1e3
            );
        }
        let phys = GpuPhysics { n_designs: chunk.len() as u32, ..key };
        // only the paths these records take are compiled in (paths.rs)
        let paths = KernelPaths::of(&designs, &particles);
        self.submit_chunk(&phys, &designs, &particles, want_particles, paths)
    }
}

/// Jobs handed to the device ([`GpuEngine::submit_jobs`]): the runs known already (designs
/// with a cpu-only effect) and the dispatches in flight.
struct Submitted {
    runs: Vec<Option<DesignRun>>,
    in_flight: Vec<InFlight>,
    want_particles: bool,
}

/// One dispatch in flight: `jobs[chunk]` under the batch-wide record `key`.
struct InFlight {
    key: GpuPhysics,
    chunk: Vec<usize>,
    pending: anyhow::Result<PendingChunk>,
}

/// The runs of `jobs[chunk]` from their dispatch's records.
fn design_runs(key: GpuPhysics, jobs: &[(&Context, &Prepared)], chunk: &[usize], r: &ChunkResult) -> Vec<DesignRun> {
    let (n_particles, teeth) = (key.n_particles as usize, key.teeth_hist as usize);
    chunk
        .iter()
        .enumerate()
        .map(|(c, &i)| {
            let prep = jobs[i].1;
            let o = &r.outcomes[c];
            let sim = from_counts(
                &r.histogram[c * teeth..(c + 1) * teeth],
                n_particles,
                o.lost as usize,
                o.flying as usize,
                o.distance_sum as f64,
                o.advance_teeth as f64 * prep.profile.pitch_len,
                prep.fill.area,
                o.iterations,
                o.bounce_sum as u64,
            );
            let parts = r
                .particles
                .as_ref()
                .map(|ps| ps[c * n_particles..(c + 1) * n_particles].iter().map(|p| particle_end(prep, p)).collect());
            (sim, parts)
        })
        .collect()
}

/// The environment's `SAWTOOTH_GPU_SLICE_DESIGNS` ([`GpuEngine::set_slice_designs`]; unset: 0).
pub(crate) fn slice_designs_from_env() -> anyhow::Result<usize> {
    const VAR: &str = "SAWTOOTH_GPU_SLICE_DESIGNS";
    match std::env::var(VAR) {
        Err(std::env::VarError::NotPresent) => Ok(0),
        Ok(v) => v.trim().parse().map_err(|_| {
            anyhow!("{VAR} must be a whole number of designs per slice (0: the whole batch at once), got '{v}'")
        }),
        Err(e) => bail!("{VAR}: {e}"),
    }
}

/// `jobs[which]` on the `cpu` engine at f32, the kernel's twin.
fn run_on_cpu(jobs: &[(&Context, &Prepared)], which: &[usize], want_particles: bool) -> Vec<DesignRun> {
    let cpu = CpuEngine { precision: Precision::F32 };
    which
        .par_iter()
        .map(|&i| {
            let (ctx, prep) = jobs[i];
            let run = cpu.run(prep, ctx, None);
            let sim = crate::model::outcome::summarise(&prep.profile, prep.fill.area, &run.particles, run.iterations);
            (sim, want_particles.then_some(run.particles))
        })
        .collect()
}

fn particle_end(prep: &Prepared, p: &GpuParticle) -> ParticleEnd {
    let state = match p.state {
        STATE_RESTING => ParticleState::Resting,
        STATE_LOST => ParticleState::Lost,
        _ => ParticleState::Flying,
    };
    let pitch = prep.profile.pitch;
    // same arithmetic as the kernel's `offset` (f32), then widened
    let o = [(p.tooth as f32) * pitch[0] as f32 + p.pos[0], (p.tooth as f32) * pitch[1] as f32 + p.pos[1]];
    ParticleEnd {
        state,
        end: if state == ParticleState::Lost { [f64::NAN; 2] } else { [o[0] as f64, o[1] as f64] },
        first_impact: (p.bounces > 0).then(|| [p.first[0] as f64, p.first[1] as f64]),
        bounces: p.bounces,
    }
}

impl BatchEvaluator for GpuEngine {
    fn backend(&self) -> &'static str {
        "gpu"
    }
    fn device(&self) -> String {
        self.describe()
    }
    /// Each kernel variant's pipeline is built on its first dispatch (`simulators`).
    fn compiles_on_first_use(&self) -> bool {
        true
    }
    /// The whole generation in one job (split where device limits demand it, or into the
    /// slices of [`GpuEngine::set_slice_designs`]).
    fn evaluate(&self, scenario: &Scenario, designs: &[Design]) -> Vec<Result<Evaluation, Invalid>> {
        self.evaluate_groups(&[(scenario.clone(), designs.to_vec())]).pop().unwrap_or_default()
    }

    /// All groups as one job: designs whose batch-wide physics agree share a dispatch even
    /// when their restitution (k_elastic, mu_friction), drag or effect parameters differ, as a
    /// calibration's candidates do; the conveyor angle lives in each design's geometry. See
    /// [`GpuEngine::run_jobs`] for the key, and for designs whose effects are cpu-only.
    /// With [`GpuEngine::set_slice_designs`] the job goes in slices, each slice's dispatches
    /// sharing as above.
    fn evaluate_groups(&self, groups: &[(Scenario, Vec<Design>)]) -> Vec<Vec<Result<Evaluation, Invalid>>> {
        let contexts: Vec<Context> = groups.iter().map(|(s, _)| Context::new(s)).collect();
        let tasks: Vec<(usize, &Design)> =
            groups.iter().enumerate().flat_map(|(g, (_, ds))| ds.iter().map(move |d| (g, d))).collect();
        // In slices: the host prepares slice k + 1 (every (group, design) pair in parallel: a
        // calibration sends one-design groups) while the device runs slice k.
        let slice = match self.slice_designs() {
            0 => tasks.len().max(1),
            n => n,
        };
        let mut prepared: Vec<Result<Prepared, Invalid>> = Vec::with_capacity(tasks.len());
        let mut sims: Vec<SimOutcome> = Vec::with_capacity(tasks.len());
        let mut finish_slice = |slice: SliceInFlight| {
            let runs = self.collect_jobs(&jobs_of(&contexts, slice.tasks, &slice.prepared), slice.submitted);
            sims.extend(runs.into_iter().map(|(sim, _)| sim));
            prepared.extend(slice.prepared);
        };
        let mut in_flight: Option<SliceInFlight> = None;
        for part in tasks.chunks(slice) {
            let part_prepared: Vec<Result<Prepared, Invalid>> =
                part.par_iter().map(|(g, d)| prepare(&groups[*g].0, d)).collect();
            let submitted = self.submit_jobs(&jobs_of(&contexts, part, &part_prepared), false);
            // the slice before ran on the device while this one was prepared
            if let Some(before) = in_flight.replace(SliceInFlight { tasks: part, prepared: part_prepared, submitted }) {
                finish_slice(before);
            }
        }
        if let Some(last) = in_flight {
            finish_slice(last);
        }
        let mut sims = sims.into_iter();
        let mut prepared = prepared.into_iter();
        groups
            .iter()
            .map(|(s, ds)| {
                prepared
                    .by_ref()
                    .take(ds.len())
                    .map(|p| match p {
                        Ok(prep) => Ok(finish_outcome(s, &prep, sims.next().expect("one outcome per valid design"))),
                        Err(e) => Err(e),
                    })
                    .collect()
            })
            .collect()
    }
}

/// A slice of `evaluate_groups`' (group, design) pairs on the device.
struct SliceInFlight<'t> {
    tasks: &'t [(usize, &'t Design)],
    prepared: Vec<Result<Prepared, Invalid>>,
    submitted: Submitted,
}

/// The valid designs of `tasks` ((group, design) pairs) with their group's context.
fn jobs_of<'a>(
    contexts: &'a [Context],
    tasks: &[(usize, &Design)],
    prepared: &'a [Result<Prepared, Invalid>],
) -> Vec<(&'a Context, &'a Prepared)> {
    tasks.iter().zip(prepared).filter_map(|((g, _), p)| p.as_ref().ok().map(|p| (&contexts[*g], p))).collect()
}

impl ParticleEngine for GpuEngine {
    fn name(&self) -> &'static str {
        "gpu"
    }
    /// One design with every particle read back. Flights are not recorded on the GPU.
    fn run(&self, prep: &Prepared, ctx: &Context, _trace: Option<&mut Vec<FlightRecord>>) -> Run {
        let (sim, parts) = self.run_prepared(ctx, &[prep], true).pop().expect("one design");
        Run { particles: parts.expect("particles requested"), iterations: sim.bounces }
    }
}
