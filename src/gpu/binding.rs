//! Small constructors for what every technique declares the same way: a uniform block's
//! bind-group entry and its buffer; and checks of the Rust side against the WGSL through naga's
//! reflection — the size of a struct (to check a `#[repr(C)]` mirror against) and the binding
//! number of each resource by name (so layouts and shaders cannot drift apart, also when a
//! performer edits a shader live).

use super::ShaderError;

/// A bind-group layout entry for a uniform block of `T` at `binding`.
pub fn uniform_entry<T>(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(size_of::<T>() as u64),
        },
        count: None,
    }
}

/// A bind-group layout entry for a storage buffer at `binding`.
pub fn storage_entry(binding: u32, visibility: wgpu::ShaderStages, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A bind-group layout entry for a compute kernel's output image at `binding`: a write-only 2-D
/// storage texture of `format`.
pub fn output_image_entry(binding: u32, format: wgpu::TextureFormat) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::WriteOnly,
            format,
            view_dimension: wgpu::TextureViewDimension::D2,
        },
        count: None,
    }
}

/// A bind-group layout entry for a filterable 2-D float texture at `binding` (a node's image).
pub fn texture_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// The two layout entries of a filtered 2-D float texture at `binding` and its sampler at
/// `binding + 1` (how a node samples an upstream node's image).
pub fn sampled_texture_entries(binding: u32, visibility: wgpu::ShaderStages) -> [wgpu::BindGroupLayoutEntry; 2] {
    [
        texture_entry(binding, visibility),
        wgpu::BindGroupLayoutEntry {
            binding: binding + 1,
            visibility,
            ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
            count: None,
        },
    ]
}

/// A bind-group entry binding all of `buffer` at `binding`.
pub fn buffer_entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource: buffer.as_entire_binding() }
}

/// A buffer for one uniform block of `T`, written with `queue.write_buffer`.
pub fn uniform_buffer<T>(device: &wgpu::Device, label: &str) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size_of::<T>() as u64,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// The byte size naga's layout gives struct `name` in `source`, if the shader declares it.
pub fn wgsl_struct_size(source: &str, name: &str) -> Option<u32> {
    let module = naga::front::wgsl::parse_str(source).ok()?;
    module.types.iter().find(|(_, t)| t.name.as_deref() == Some(name)).and_then(|(_, t)| match &t.inner {
        naga::TypeInner::Struct { span, .. } => Some(*span),
        _ => None,
    })
}

/// Checks that each `(name, binding)` the Rust side binds in group 0 is a global of that name at
/// that binding in `source`. The error points at the WGSL declaration and says both numbers.
pub fn check_bindings(origin: &str, source: &str, expected: &[(&str, u32)]) -> Result<(), ShaderError> {
    let module = super::validate_wgsl(origin, source)?;
    for &(name, binding) in expected {
        let found = module.global_variables.iter().find(|(_, g)| g.name.as_deref() == Some(name));
        let error = |line, column, message| ShaderError { origin: origin.into(), line, column, message };
        let Some((handle, global)) = found else {
            return Err(error(
                1,
                1,
                format!(
                    "the engine binds '{name}' at @group(0) @binding({binding}), but the shader declares no '{name}'"
                ),
            ));
        };
        let at = global.binding.as_ref().map(|b| (b.group, b.binding));
        if at != Some((0, binding)) {
            let location = module.global_variables.get_span(handle).location(source);
            let declared = at.map_or("no binding".to_string(), |(g, b)| format!("@group({g}) @binding({b})"));
            return Err(error(
                location.line_number,
                location.line_position,
                format!("'{name}' is declared at {declared}; the engine binds it at @group(0) @binding({binding})"),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const SHADER: &str = "@group(0) @binding(0) var<uniform> u: vec4<f32>;\n@group(0) @binding(2) var<storage, read> data: array<f32>;\n@compute @workgroup_size(1) fn main() { _ = u; _ = data[0]; }\n";

    #[test]
    fn bindings_are_checked_by_name_with_the_declaration_located() {
        assert!(check_bindings("s.wgsl", SHADER, &[("u", 0), ("data", 2)]).is_ok());
        let moved = check_bindings("s.wgsl", SHADER, &[("data", 1)]).unwrap_err();
        assert_eq!(moved.line, 2, "the declaration of data: {moved}");
        assert!(moved.message.contains("@binding(2)") && moved.message.contains("@binding(1)"), "{moved}");
        let missing = check_bindings("s.wgsl", SHADER, &[("gone", 3)]).unwrap_err();
        assert!(missing.message.contains("no 'gone'"), "{missing}");
    }
}
