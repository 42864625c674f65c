//! Small constructors for what every technique declares the same way: a uniform block's
//! bind-group entry and its buffer; and checks of the Rust side against the WGSL through naga's
//! reflection — the size of a struct (to check a `#[repr(C)]` mirror against) and the binding
//! number of each resource by name (so layouts and shaders cannot drift apart, also when a
//! performer edits a shader live).

use std::sync::atomic::{AtomicBool, Ordering};

use super::ShaderError;

/// Whether parameter blocks are bound as read-only storage buffers instead of uniform buffers
/// (see [`blocks_in_storage`]).
static BLOCKS_IN_STORAGE: AtomicBool = AtomicBool::new(false);

/// Whether this process binds its parameter blocks (WGSL `var<uniform>`) as read-only storage
/// buffers: on Mesa's lavapipe. Its Vulkan driver "inlines" uniform values that steer loops and
/// branches by compiling a new shader variant at every dispatch that binds such a pipeline —
/// and keeps every variant until the pipeline is destroyed: Mesa 22.3 (Debian 12) grew by ~33 KB
/// per dispatch (17 MB/s at 320×180) in StarGlow's fused passes, the tessellation and space
/// colonization. It inlines only values read from uniform buffers; storage buffers hold the same
/// bytes in the same layout (the WGSL layout rules are one for both) and are never inlined.
/// Set once when a device is made ([`super::Gpu`]); every device of a process is the same kind.
pub fn blocks_in_storage() -> bool {
    BLOCKS_IN_STORAGE.load(Ordering::Relaxed)
}

/// Binds parameter blocks as storage from now on (`true`: a lavapipe device was made).
pub(super) fn set_blocks_in_storage(on: bool) {
    BLOCKS_IN_STORAGE.store(on, Ordering::Relaxed);
}

/// The binding type of a parameter block: a uniform buffer, or where [`blocks_in_storage`] a
/// read-only storage buffer.
pub fn block_binding(has_dynamic_offset: bool, min_binding_size: Option<wgpu::BufferSize>) -> wgpu::BindingType {
    let ty = if blocks_in_storage() {
        wgpu::BufferBindingType::Storage { read_only: true }
    } else {
        wgpu::BufferBindingType::Uniform
    };
    wgpu::BindingType::Buffer { ty, has_dynamic_offset, min_binding_size }
}

/// The usages of a parameter block's buffer: bound as a uniform or (lavapipe) a storage buffer,
/// written from the CPU.
pub const BLOCK_USAGE: wgpu::BufferUsages =
    wgpu::BufferUsages::UNIFORM.union(wgpu::BufferUsages::STORAGE).union(wgpu::BufferUsages::COPY_DST);

/// `module` with its uniform globals moved to read-only storage where [`blocks_in_storage`]
/// (the shader side of [`block_binding`]); otherwise as it is.
pub fn with_blocks_bound(mut module: naga::Module) -> naga::Module {
    if blocks_in_storage() {
        for (_, global) in module.global_variables.iter_mut() {
            if global.space == naga::AddressSpace::Uniform {
                global.space = naga::AddressSpace::Storage { access: naga::StorageAccess::LOAD };
            }
        }
    }
    module
}

/// A bind-group layout entry for a uniform block of `T` at `binding`.
pub fn uniform_entry<T>(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: block_binding(false, wgpu::BufferSize::new(size_of::<T>() as u64)),
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
        usage: BLOCK_USAGE,
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
