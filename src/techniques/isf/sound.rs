//! Sound as textures for ISF `audio` and `audioFFT` inputs: one row of half floats, written
//! each frame from the audio analysis' snapshot.

use crate::graph::PersistentTexture;
use crate::params::AudioSnapshot;

/// One sound input's texture.
pub struct AudioTexture {
    /// The texture: one row, `width` texels.
    pub texture: PersistentTexture,
    /// Whether it holds the spectrum (else the waveform).
    spectrum: bool,
}

impl AudioTexture {
    /// `width` samples or bins wide, holding silence.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, name: &str, width: u32, spectrum: bool) -> Self {
        let texture = PersistentTexture::new(device, name, (width, 1), AUDIO_FORMAT);
        let made = Self { texture, spectrum };
        made.write(queue, &AudioSnapshot::default());
        made
    }

    /// Writes what `audio` heard, resampled to the texture's width: a spectrum as 0–1 per bin, a
    /// waveform as ISF hosts give it (0.5 is silence, 0 and 1 full scale), in every channel.
    pub fn write(&self, queue: &wgpu::Queue, audio: &AudioSnapshot) {
        let width = self.texture.texture.width() as usize;
        let source = if self.spectrum { &audio.spectrum } else { &audio.wave };
        let value = |i: usize| -> f32 {
            let x = if source.is_empty() { 0.0 } else { source[(i * source.len() / width).min(source.len() - 1)] };
            if self.spectrum { x.clamp(0.0, 1.0) } else { (x * 0.5 + 0.5).clamp(0.0, 1.0) }
        };
        let texels: Vec<u16> = (0..width)
            .flat_map(|i| {
                let v = half::f16::from_f32(value(i)).to_bits();
                [v, v, v, half::f16::ONE.to_bits()]
            })
            .collect();
        queue.write_texture(
            self.texture.texture.as_image_copy(),
            bytemuck::cast_slice(&texels),
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(8 * width as u32), rows_per_image: Some(1) },
            self.texture.texture.size(),
        );
    }
}

/// Sound textures: half floats (filterable everywhere).
const AUDIO_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// Samples or bins of a sound texture when the input asks for no `MAX`.
pub const AUDIO_WIDTH: u32 = 256;
