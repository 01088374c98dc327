//! Reading from the card: ranges of buffers copied into one mapped staging buffer, the copy
//! started without waiting and taken later (the app asks at one tick and takes at the next),
//! the staging buffers kept between reads (the app reads every tick).

use super::context::{Gpu, GpuError};
use super::kernel::empty;
use std::sync::Mutex;
use std::sync::mpsc::Receiver;

/// A read under way: the staging buffer the copy went to, the bytes it holds, and the map's
/// answer.
#[derive(Debug)]
pub(super) struct Read {
    staging: wgpu::Buffer,
    /// Which of [`ReadBack`]'s staging buffers it is.
    slot: usize,
    total: u64,
    mapped: Receiver<Result<(), wgpu::BufferAsyncError>>,
}

/// The staging buffers, one a slot (the step's state, and its summary), kept for the next
/// read: a new one only when a read is larger than the last.
#[derive(Debug, Default)]
pub(super) struct ReadBack {
    staging: [Mutex<Option<wgpu::Buffer>>; 2],
}

impl ReadBack {
    /// Copies the ranges `(buffer, offset, length)`, one after the other, into the staging
    /// buffer of `slot` and asks for it mapped, without waiting.
    pub(super) fn start(
        &self,
        gpu: &Gpu,
        slot: usize,
        ranges: &[(&wgpu::Buffer, u64, u64)],
    ) -> Result<Read, GpuError> {
        let total: u64 = ranges.iter().map(|r| r.2).sum();
        let mut kept = self.staging[slot]
            .lock()
            .map_err(|e| GpuError::ReadBack(e.to_string()))?;
        let size = total.max(8).next_multiple_of(8);
        let staging = match kept.take() {
            Some(b) if b.size() >= size => b,
            _ => {
                let usage = wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST;
                empty(&gpu.device, "read back", size, usage)
            }
        };
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("read back"),
            });
        let mut at = 0;
        for &(buffer, offset, length) in ranges {
            if length > 0 {
                encoder.copy_buffer_to_buffer(buffer, offset, &staging, at, length);
            }
            at += length;
        }
        gpu.queue.submit([encoder.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        Ok(Read {
            staging,
            slot,
            total,
            mapped: rx,
        })
    }

    /// Waits for a started read (at once if the card has finished it) and returns its bytes;
    /// the staging buffer is kept for the next.
    pub(super) fn end(&self, gpu: &Gpu, read: Read) -> Result<Vec<u8>, GpuError> {
        let Read {
            staging,
            slot,
            total,
            mapped,
        } = read;
        let done = match mapped.try_recv() {
            Ok(r) => r,
            Err(_) => {
                gpu.wait()?;
                mapped
                    .recv()
                    .map_err(|e| GpuError::ReadBack(e.to_string()))?
            }
        };
        done.map_err(|e| GpuError::ReadBack(e.to_string()))?;
        let bytes = staging.slice(..).get_mapped_range()[..total as usize].to_vec();
        staging.unmap();
        if let Ok(mut kept) = self.staging[slot].lock() {
            *kept = Some(staging);
        }
        Ok(bytes)
    }

    /// The bytes of the ranges, waiting for the card.
    pub(super) fn now(
        &self,
        gpu: &Gpu,
        ranges: &[(&wgpu::Buffer, u64, u64)],
    ) -> Result<Vec<u8>, GpuError> {
        let read = self.start(gpu, 0, ranges)?;
        self.end(gpu, read)
    }
}
