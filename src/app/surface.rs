//! Choosing how to draw into a window's surface from what it offers.

/// The colour format and alpha mode for a surface, or one sentence on why none fits. egui and the
/// display encode both write sRGB-encoded bytes themselves, so a non-sRGB format is preferred.
pub fn choose_surface_format(
    caps: &wgpu::SurfaceCapabilities,
    adapter: &str,
) -> Result<(wgpu::TextureFormat, wgpu::CompositeAlphaMode), String> {
    let format = caps.formats.iter().copied().find(|f| !f.is_srgb()).or(caps.formats.first().copied()).ok_or_else(
        || {
            format!(
                "{adapter} cannot draw into this window (its surface offers no formats); try --backend gl, another --adapter, or render off-screen with `indra render`"
            )
        },
    )?;
    let alpha = caps.alpha_modes.first().copied().unwrap_or(wgpu::CompositeAlphaMode::Auto);
    Ok((format, alpha))
}

/// Configures `surface` of `window` for `gpu` (a format and alpha mode it offers, vsync, two
/// frames in flight) and returns the configuration, or one sentence on why it cannot be drawn.
pub fn configure_surface(
    surface: &wgpu::Surface<'_>,
    window: &winit::window::Window,
    gpu: &crate::gpu::Gpu,
) -> Result<wgpu::SurfaceConfiguration, String> {
    let caps = surface.get_capabilities(&gpu.adapter);
    let (format, alpha_mode) = choose_surface_format(&caps, &gpu.adapter_label())?;
    let size = window.inner_size();
    let config = wgpu::SurfaceConfiguration {
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        format,
        color_space: wgpu::SurfaceColorSpace::Auto,
        width: size.width.max(1),
        height: size.height.max(1),
        present_mode: wgpu::PresentMode::AutoVsync,
        desired_maximum_frame_latency: 2,
        alpha_mode,
        view_formats: vec![],
    };
    surface.configure(&gpu.device, &config);
    Ok(config)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_surface_that_offers_nothing_is_a_sentence_not_a_panic() {
        let nothing = wgpu::SurfaceCapabilities { formats: Vec::new(), alpha_modes: Vec::new(), ..Default::default() };
        let e = choose_surface_format(&nothing, "llvmpipe").unwrap_err();
        assert!(e.contains("llvmpipe") && e.contains("--backend gl"), "{e}");
    }

    #[test]
    fn a_non_srgb_format_is_preferred_and_a_missing_alpha_mode_is_auto() {
        let caps = wgpu::SurfaceCapabilities {
            formats: vec![wgpu::TextureFormat::Bgra8UnormSrgb, wgpu::TextureFormat::Bgra8Unorm],
            alpha_modes: Vec::new(),
            ..Default::default()
        };
        let (format, alpha) = choose_surface_format(&caps, "gpu").unwrap();
        assert_eq!(format, wgpu::TextureFormat::Bgra8Unorm);
        assert_eq!(alpha, wgpu::CompositeAlphaMode::Auto);
    }
}
