//! WGSL compilation: naga parses and validates first so that every error carries file:line:col,
//! then wgpu builds the module inside an error scope so nothing reaches the panicking default.

use std::fmt;

/// A shader that failed to parse, validate or build, located in its file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ShaderError {
    /// Where the source came from (path or `<embedded>/…`).
    pub origin: String,
    /// 1-based line, if known.
    pub line: u32,
    /// 1-based column, if known.
    pub column: u32,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for ShaderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}: {}", self.origin, self.line, self.column, self.message)
    }
}

impl std::error::Error for ShaderError {}

/// Parses and validates WGSL with naga; the module is returned for reflection.
pub fn validate_wgsl(origin: &str, source: &str) -> Result<naga::Module, ShaderError> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| {
        let (line, column) = e.location(source).map(|l| (l.line_number, l.line_position)).unwrap_or((1, 1));
        let labels: Vec<String> = e.labels().filter(|(_, l)| !l.is_empty()).map(|(_, l)| l.to_string()).collect();
        let mut message = e.message().to_string();
        if !labels.is_empty() {
            message = format!("{message} ({})", labels.join("; "));
        }
        ShaderError { origin: origin.to_string(), line, column, message }
    })?;
    validate_module(origin, source, &module)?;
    Ok(module)
}

/// Validates a parsed module (WGSL or GLSL), an error located in `source` by the narrowest span
/// naga gives and its cause chain joined into one line.
pub fn validate_module(
    origin: &str,
    source: &str,
    module: &naga::Module,
) -> Result<naga::valid::ModuleInfo, ShaderError> {
    let mut validator =
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all());
    validator.validate(module).map_err(|e| {
        // Spans go from the whole function down to the faulty expression: report the narrowest.
        let (line, column) = e
            .spans()
            .map(|(span, _)| span.location(source))
            .filter(|l| l.length > 0)
            .min_by_key(|l| l.length)
            .map(|l| (l.line_number, l.line_position))
            .unwrap_or((1, 1));
        // The error chain names the function and the actual fault; join it into one line.
        let mut message = e.as_inner().to_string();
        let mut cause = std::error::Error::source(e.as_inner());
        while let Some(c) = cause {
            message.push_str(": ");
            message.push_str(&c.to_string());
            cause = c.source();
        }
        ShaderError { origin: origin.to_string(), line, column, message }
    })
}

/// Validates `source` and creates the wgpu shader module inside a validation error scope; the
/// naga module comes along for reflection (workgroup sizes, struct layouts).
pub fn compile_wgsl(
    device: &wgpu::Device,
    origin: &str,
    source: &str,
) -> Result<(wgpu::ShaderModule, naga::Module), ShaderError> {
    let reflection = validate_wgsl(origin, source)?;
    let module = validated(device, origin, || {
        // On lavapipe the parameter blocks are storage buffers (see `blocks_in_storage`).
        let source = if super::blocks_in_storage() {
            wgpu::ShaderSource::Naga(std::borrow::Cow::Owned(super::with_blocks_bound(reflection.clone())))
        } else {
            wgpu::ShaderSource::Wgsl(source.into())
        };
        device.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some(origin), source })
    })?;
    Ok((module, reflection))
}

/// Several shader files joined into one module's source (a shader that builds on another's
/// functions), remembering where each file starts so that an error is reported in its own file.
#[derive(Clone, Debug)]
pub struct JoinedSource {
    /// The joined text.
    pub source: String,
    /// Each file's origin and the joined line its first line became (1-based), in order.
    parts: Vec<(String, u32)>,
}

impl JoinedSource {
    /// Joins `(origin, source)` files in order.
    pub fn new(files: &[(String, String)]) -> Self {
        let (mut source, mut parts) = (String::new(), Vec::new());
        for (origin, text) in files {
            parts.push((origin.clone(), source.lines().count() as u32 + 1));
            source.push_str(text);
            if !text.ends_with('\n') {
                source.push('\n');
            }
        }
        Self { source, parts }
    }

    /// `source` (read from `origin`) after the files it builds on, named by `// extends: NAME`
    /// lines at its top (one or more; each base may extend others), bases first, each file once;
    /// `load` reads a file by name as `(origin, source)`. A shader without such a line stands
    /// alone.
    pub fn with_bases(
        origin: &str,
        source: &str,
        load: impl Fn(&str) -> Result<(String, String), String>,
    ) -> Result<Self, String> {
        let mut files = Vec::new();
        add_with_bases(&mut files, &mut vec![origin.to_string()], (origin.to_string(), source.to_string()), &load)?;
        Ok(Self::new(&files))
    }

    /// Parses and validates the joined text, errors located in their own file.
    pub fn validate(&self) -> Result<naga::Module, ShaderError> {
        validate_wgsl(self.origin(), &self.source).map_err(|e| self.relocate(e))
    }

    /// The origin to build with: the last file's (the one that adds the entry points).
    pub fn origin(&self) -> &str {
        self.parts.last().map_or("<joined>", |(origin, _)| origin)
    }

    /// `error`, located in the joined text, moved to the file and line it came from.
    pub fn relocate(&self, mut error: ShaderError) -> ShaderError {
        if let Some((origin, first)) = self.parts.iter().rev().find(|(_, first)| *first <= error.line) {
            error.origin.clone_from(origin);
            error.line = error.line - first + 1;
        }
        error
    }
}

impl JoinedSource {
    /// Whether the file named `name` (as `// extends:` lines name it) is one of those joined.
    pub fn joins(&self, name: &str) -> bool {
        self.parts.iter().any(|(origin, _)| std::path::Path::new(origin).file_name().is_some_and(|f| f == name))
    }
}

/// Validates shader file `name` (read from `origin` as `source`) as the engine uses it. A file
/// that other shaders extend may call hooks only they define, so it is validated through each
/// of them that nothing extends in turn, with this text in place of the stored one; any other
/// file after its own bases. `shaders` names every shader that might extend it; `load` reads
/// one by name as `(origin, source)`. Errors are located in their own file.
pub fn validate_as_used(
    name: &str,
    (origin, source): (&str, &str),
    shaders: &[String],
    load: impl Fn(&str) -> Result<(String, String), String>,
) -> Result<(), String> {
    let edited = |n: &str| if n == name { Ok((origin.to_string(), source.to_string())) } else { load(n) };
    // Another file's own broken chain is its error, reported when it is checked.
    let extenders: Vec<(&str, JoinedSource)> = shaders
        .iter()
        .filter(|n| n.as_str() != name)
        .filter_map(|n| {
            let (o, s) = load(n).ok()?;
            extended_files(&s).next()?;
            let joined = JoinedSource::with_bases(&o, &s, edited).ok()?;
            joined.joins(name).then_some((n.as_str(), joined))
        })
        .collect();
    if extenders.is_empty() {
        let joined = JoinedSource::with_bases(origin, source, &load)?;
        return joined.validate().map(|_| ()).map_err(|e| e.to_string());
    }
    let extended = |n: &str| extenders.iter().any(|(other, joined)| *other != n && joined.joins(n));
    for (_, joined) in extenders.iter().filter(|(n, _)| !extended(n)) {
        joined.validate().map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// Files deeper than this are taken for a circle.
const MAX_EXTENDS_DEPTH: usize = 6;

/// Appends `file` to `files` after its bases (depth first, each file once); `path` is the chain
/// of files being added, to tell a circle.
fn add_with_bases(
    files: &mut Vec<(String, String)>,
    path: &mut Vec<String>,
    file: (String, String),
    load: &impl Fn(&str) -> Result<(String, String), String>,
) -> Result<(), String> {
    for base in extended_files(&file.1) {
        if files.iter().any(|(o, _)| o.ends_with(base)) {
            continue;
        }
        if path.len() > MAX_EXTENDS_DEPTH || path.iter().any(|o| o.ends_with(base)) {
            return Err(format!("{}: `// extends: {base}` goes round in a circle", path[0]));
        }
        let loaded = load(base).map_err(|e| format!("{}: extends {base}: {e}", file.0))?;
        path.push(loaded.0.clone());
        add_with_bases(files, path, loaded, load)?;
        path.pop();
    }
    files.push(file);
    Ok(())
}

/// The files a shader builds on: `NAME` of each `// extends: NAME` line among its leading
/// comments.
fn extended_files(source: &str) -> impl Iterator<Item = &str> {
    source
        .lines()
        .map(str::trim)
        .take_while(|l| l.is_empty() || l.starts_with("//"))
        .filter_map(|l| l.strip_prefix("// extends:"))
        .map(str::trim)
}

/// Runs `build` (creating modules or pipelines) inside a validation error scope: what naga
/// accepted but wgpu did not (e.g. bindings that differ from the layout) becomes a
/// [`ShaderError`] at `origin` instead of a panic.
pub fn validated<R>(device: &wgpu::Device, origin: &str, build: impl FnOnce() -> R) -> Result<R, ShaderError> {
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let built = build();
    match pollster::block_on(scope.pop()) {
        None => Ok(built),
        Some(e) => Err(ShaderError { origin: origin.to_string(), line: 1, column: 1, message: e.to_string() }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_error_in_a_joined_source_is_located_in_its_own_file() {
        let base = ("base.wgsl".to_string(), "fn one() -> f32 {\n    return 1.0;\n}".to_string());
        let top = ("top.wgsl".to_string(), "fn two() -> f32 {\n    return one() + 1.0\n}\n".to_string());
        let joined = JoinedSource::new(&[base, top]);
        assert_eq!(joined.origin(), "top.wgsl");
        let error = joined.relocate(validate_wgsl(joined.origin(), &joined.source).unwrap_err());
        assert_eq!((error.origin.as_str(), error.line), ("top.wgsl", 3), "{error}");
        let early = joined.relocate(ShaderError { origin: "x".into(), line: 2, column: 5, message: String::new() });
        assert_eq!((early.origin.as_str(), early.line, early.column), ("base.wgsl", 2, 5));
    }

    #[test]
    fn a_shader_that_extends_another_is_validated_after_it() {
        let files = |name: &str| match name {
            "base.wgsl" => Ok(("lib/base.wgsl".to_string(), "fn one() -> f32 {\n    return 1.0;\n}\n".to_string())),
            other => Err(format!("no {other}")),
        };
        let top = "// Adds two.\n// extends: base.wgsl\n\nfn two() -> f32 {\n    return one() + 1.0;\n}\n";
        let joined = JoinedSource::with_bases("top.wgsl", top, files).unwrap();
        assert!(joined.validate().is_ok());
        let broken = top.replace("one() + 1.0", "one() + true");
        let error = JoinedSource::with_bases("top.wgsl", &broken, files).unwrap().validate().unwrap_err();
        assert_eq!((error.origin.as_str(), error.line), ("top.wgsl", 5), "{error}");
        let missing = JoinedSource::with_bases("top.wgsl", &top.replace("base.wgsl", "gone.wgsl"), files);
        assert!(missing.unwrap_err().contains("extends gone.wgsl: no gone.wgsl"));
        assert!(JoinedSource::with_bases("top.wgsl", "fn alone() {}", files).unwrap().validate().is_ok());
    }

    #[test]
    fn a_base_with_hooks_is_validated_through_the_files_that_extend_it() {
        // base.wgsl calls hook(), which only its extenders define; mid.wgsl extends it and is
        // itself extended by top.wgsl, so only top.wgsl and side.wgsl are whole shaders.
        let stored = |name: &str| -> Result<(String, String), String> {
            let text = match name {
                "base.wgsl" => "fn twice() -> f32 {\n    return hook() * 2.0;\n}\n",
                "mid.wgsl" => "// extends: base.wgsl\nfn plus() -> f32 {\n    return twice() + 1.0;\n}\n",
                "top.wgsl" => {
                    "// extends: mid.wgsl\nfn hook() -> f32 {\n    return 1.0;\n}\nfn four() -> f32 {\n    return plus() + 1.0;\n}\n"
                }
                "side.wgsl" => "// extends: base.wgsl\nfn hook() -> f32 {\n    return 3.0;\n}\n",
                "alone.wgsl" => "fn alone() -> f32 {\n    return 1.0;\n}\n",
                other => return Err(format!("no {other}")),
            };
            Ok((format!("dir/{name}"), text.to_string()))
        };
        let names: Vec<String> =
            ["alone.wgsl", "base.wgsl", "mid.wgsl", "side.wgsl", "top.wgsl"].map(String::from).to_vec();
        let check = |name: &str, text: &str| validate_as_used(name, (&format!("dir/{name}"), text), &names, stored);
        let base = stored("base.wgsl").unwrap().1;
        assert!(JoinedSource::with_bases("dir/base.wgsl", &base, stored).unwrap().validate().is_err(), "not alone");
        assert_eq!(check("base.wgsl", &base), Ok(()));
        assert_eq!(check("mid.wgsl", &stored("mid.wgsl").unwrap().1), Ok(()));
        // The edited text is the one checked, its error located in it.
        let broken = base.replace("hook() * 2.0", "hook() * true");
        let error = check("base.wgsl", &broken).unwrap_err();
        assert!(error.starts_with("dir/base.wgsl:2:"), "{error}");
        // A hook one extender lacks is that extender's error, found through the base.
        let renamed = base.replace("hook()", "hooked()");
        assert!(check("base.wgsl", &renamed).unwrap_err().contains("hooked"));
        // A file nothing extends is checked after its own bases, as before.
        assert_eq!(check("alone.wgsl", "fn alone() -> f32 {\n    return 2.0;\n}\n"), Ok(()));
        assert!(check("side.wgsl", "// extends: base.wgsl\nfn other() {}\n").is_err(), "side no longer hooks");
    }

    #[test]
    fn two_bases_that_share_a_base_join_it_once() {
        let files = |name: &str| -> Result<(String, String), String> {
            let text = match name {
                "one.wgsl" => "fn one() -> f32 {\n    return 1.0;\n}\n",
                "left.wgsl" => "// extends: one.wgsl\nfn left() -> f32 {\n    return one();\n}\n",
                "right.wgsl" => "// extends: one.wgsl\nfn right() -> f32 {\n    return one();\n}\n",
                "round.wgsl" => "// extends: round.wgsl\n",
                other => return Err(format!("no {other}")),
            };
            Ok((name.to_string(), text.to_string()))
        };
        let top =
            "// extends: left.wgsl\n// extends: right.wgsl\nfn both() -> f32 {\n    return left() + right();\n}\n";
        let joined = JoinedSource::with_bases("top.wgsl", top, files).unwrap();
        assert!(joined.validate().is_ok(), "{:?}", joined.validate());
        assert_eq!(joined.source.matches("fn one()").count(), 1);
        let circle = JoinedSource::with_bases("top.wgsl", "// extends: round.wgsl\n", files);
        assert!(circle.unwrap_err().contains("goes round in a circle"));
    }

    #[test]
    fn syntax_error_is_located() {
        let src = "@compute @workgroup_size(1)\nfn main() {\n    let x = 1.0 +;\n}\n";
        let err = validate_wgsl("broken.wgsl", src).unwrap_err();
        assert_eq!((err.line, err.column > 1), (3, true), "{err}");
        assert!(err.to_string().starts_with("broken.wgsl:3:"), "{err}");
    }

    #[test]
    fn type_error_is_located() {
        let src = "fn f() -> f32 {\n    return 1u;\n}\n";
        let err = validate_wgsl("typed.wgsl", src).unwrap_err();
        assert_eq!(err.line, 2, "{err}");
    }

    #[test]
    fn valid_shader_passes() {
        assert!(validate_wgsl("ok.wgsl", "fn f() -> f32 { return 1.0; }").is_ok());
    }
}
