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
