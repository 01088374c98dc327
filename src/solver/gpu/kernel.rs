//! How a pass's kernels are built, fed and dispatched: the pieces every pass on the card
//! shares (a WGSL module in the chosen precision, a compute pipeline whose layout the kernel
//! implies, buffers that are never empty, settings packed as the kernels' `Params`, one
//! compute pass a submit), and the numbers' encoding to and from the card's bytes.

use super::context::{Gpu, Precision};
use crate::solver::contact::obstacle::{MIN_THICKNESS, SLOP};
use glam::DVec2;
use wgpu::util::DeviceExt;

/// The most work groups along one side of a dispatch.
const MAX_GROUPS: u32 = 65_535;

/// A compute pipeline for one entry point of `module`, its layout the one the kernel implies.
pub(super) fn pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    entry: &str,
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: None,
        module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// A dispatch's shape for `threads` threads in work groups of `group`: at most [`MAX_GROUPS`]
/// groups a row, and at least one group (a kernel indexes its thread as `x + y · row`).
pub(super) fn shape(threads: u64, group: u32) -> (u32, u32) {
    let groups = threads.div_ceil(u64::from(group)).max(1) as u32;
    let across = groups.min(MAX_GROUPS);
    (across, groups.div_ceil(across))
}

/// One compute pass, recorded by `record`, submitted (not waited for).
pub(super) fn submit(gpu: &Gpu, label: &str, record: impl FnOnce(&mut wgpu::ComputePass)) {
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: None,
        });
        record(&mut pass);
    }
    gpu.queue.submit([encoder.finish()]);
}

/// One dispatch of `pipeline` with `group` over `groups` work groups.
pub(super) fn dispatch(
    pass: &mut wgpu::ComputePass,
    pipeline: &wgpu::ComputePipeline,
    group: &wgpu::BindGroup,
    groups: (u32, u32),
) {
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.dispatch_workgroups(groups.0, groups.1, 1);
}

/// A storage or uniform buffer holding `contents`, never empty (a scene without springs still
/// binds its links): at least one vector of the widest precision.
pub(super) fn buffer(
    device: &wgpu::Device,
    label: &str,
    contents: &[u8],
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    let mut padded = contents.to_vec();
    padded.resize(contents.len().max(16), 0);
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: &padded,
        usage,
    })
}

/// A kernel's settings: a uniform buffer of `size` bytes, written by [`write_settings`].
pub(super) fn settings_buffer(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    empty(
        device,
        label,
        size,
        wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
    )
}

/// A buffer of `size` bytes, zeroed, that a kernel or a copy fills.
pub(super) fn empty(
    device: &wgpu::Device,
    label: &str,
    size: u64,
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage,
        mapped_at_creation: false,
    })
}

/// Writes a kernel's settings as its WGSL `Params` lays them out: four `u32`s, then the numbers
/// one after another in `precision` (each kernel orders its fields so that they pack so), the
/// rest of the uniform buffer zeroed.
pub(super) fn write_settings(
    queue: &wgpu::Queue,
    params: &wgpu::Buffer,
    precision: Precision,
    header: [u32; 4],
    values: &[f64],
) {
    let mut bytes: Vec<u8> = header.iter().flat_map(|v| v.to_le_bytes()).collect();
    bytes.extend(reals(values, precision));
    bytes.resize(params.size() as usize, 0);
    queue.write_buffer(params, 0, &bytes);
}

/// Bind group entries: each buffer whole at its binding.
pub(super) fn entries<'a>(list: &[(u32, &'a wgpu::Buffer)]) -> Vec<wgpu::BindGroupEntry<'a>> {
    list.iter()
        .map(|&(binding, b)| wgpu::BindGroupEntry {
            binding,
            resource: b.as_entire_binding(),
        })
        .collect()
}

/// A kernel's module, its `real` alias set to the precision.
pub(super) fn shader(
    device: &wgpu::Device,
    source: &str,
    label: &str,
    precision: Precision,
) -> wgpu::ShaderModule {
    let source = match precision {
        Precision::F32 => source.to_string(),
        Precision::F64 => source
            .replace("alias real = f32;", "alias real = f64;")
            .replace(
                "const MIN_THICKNESS: real = 1e-5;",
                &format!("const MIN_THICKNESS: real = {MIN_THICKNESS:e};"),
            )
            .replace(
                "const SLOP: real = 1e-6;",
                &format!("const SLOP: real = {SLOP:e};"),
            ),
    };
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

/// `values` as the card reads them in `precision`.
pub(super) fn reals(values: &[f64], precision: Precision) -> Vec<u8> {
    match precision {
        Precision::F32 => values
            .iter()
            .flat_map(|&v| (v as f32).to_le_bytes())
            .collect(),
        Precision::F64 => values.iter().flat_map(|&v| v.to_le_bytes()).collect(),
    }
}

/// Vectors as the card reads them: x, y, one after the other.
pub(super) fn vectors(values: &[DVec2], precision: Precision) -> Vec<u8> {
    let flat: Vec<f64> = values.iter().flat_map(|v| [v.x, v.y]).collect();
    reals(&flat, precision)
}

/// The numbers in the bytes a read brought back.
pub(super) fn from_bytes(bytes: &[u8], precision: Precision) -> Vec<f64> {
    match precision {
        Precision::F32 => bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
            .collect(),
        Precision::F64 => bytes
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect(),
    }
}
