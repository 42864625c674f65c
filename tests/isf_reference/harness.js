// Loads the reference renderer from its package's own CommonJS sources (`files`: path in the
// package → text), as a bundler would. The package's prebuilt bundle cannot serve: its build made
// the vendored math.js strict, and pass sizes then throw. Returns the package's exports.
window.isfReferenceLoad = (files) => {
  const modules = {};
  const resolve = (from, spec) => {
    const parts = from.split('/').slice(0, -1);
    for (const part of spec.split('/')) {
      if (part === '..') parts.pop();
      else if (part !== '.') parts.push(part);
    }
    const path = parts.join('/');
    return path.endsWith('.js') ? path : `${path}.js`;
  };
  const load = (path) => {
    if (!(path in files)) throw new Error(`the reference renderer has no ${path}`);
    if (!modules[path]) {
      const module = { exports: {} };
      modules[path] = module;
      // eslint-disable-next-line no-new-func
      // A bare name is a Node built-in: math.js asks for `crypto`, which in a page is the
      // browser's own (what math.js itself takes when loaded without a module system).
      const require = (spec) => (spec.startsWith('.') ? load(resolve(path, spec)) : window[spec]);
      new Function('require', 'module', 'exports', files[path])(require, module, module.exports);
    }
    return modules[path].exports;
  };
  window.ISF = load('lib/main.js');
  return Object.keys(window.ISF);
};

// Renders one ISF file with the reference renderer (npm `interactive-shader-format`, evaluated in
// this page first as `window.ISF`), with the inputs and clock indra gives the same file in the
// comparison test: the same images, the values indra's header reading gives inputs that have no
// DEFAULT, progress 0.5 for transitions, and TIME = frame × dt on a fixed clock rather than the
// wall clock. Returns the last frame's RGBA bytes, top row first, or { error }.
window.isfReferenceRender = (job) => {
  const canvas = document.createElement('canvas');
  canvas.width = job.width;
  canvas.height = job.height;
  const gl = canvas.getContext('webgl', { preserveDrawingBuffer: true, premultipliedAlpha: false, antialias: false });
  if (!gl) return { error: 'no WebGL in this browser' };
  // FLOAT passes need WebGL 1's float textures, which a page turns on.
  gl.getExtension('OES_texture_float');
  gl.getExtension('OES_texture_float_linear');
  const renderer = new window.ISF.Renderer(gl);
  renderer.loadSource(job.fragment, job.vertex || undefined);
  if (!renderer.valid) return { error: `reference: ${renderer.error && (renderer.error.message || JSON.stringify(renderer.error))}` };

  // Images as 2D canvases (the renderer uploads canvases; their bytes are not colour-managed).
  const picture = (rgba) => {
    const c = document.createElement('canvas');
    c.width = job.width;
    c.height = job.height;
    c.getContext('2d').putImageData(new ImageData(new Uint8ClampedArray(rgba), job.width, job.height), 0, 0);
    return c;
  };
  const pictures = job.images.map(picture);
  const images = {};
  const inputs = renderer.model.inputs || [];
  let imageCount = 0;
  for (const input of inputs) {
    if (input.TYPE === 'image') {
      images[input.NAME] = pictures[input.NAME === 'endImage' ? 1 : Math.min(imageCount, 1)];
      imageCount += 1;
    }
  }
  // What indra gives an input without a DEFAULT: a float or point its range's nearest value to
  // 0, a long its first value, a colour opaque black (GL leaves such uniforms 0).
  const clamp = (v, lo, hi) => Math.min(Math.max(v, lo ?? v), hi ?? v);
  for (const input of inputs) {
    if (input.DEFAULT !== undefined) continue;
    if (input.TYPE === 'float') renderer.setValue(input.NAME, clamp(0, input.MIN, input.MAX));
    if (input.TYPE === 'long' && input.VALUES) renderer.setValue(input.NAME, input.VALUES[0]);
    if (input.TYPE === 'color') renderer.setValue(input.NAME, [0, 0, 0, 1]);
    if (input.TYPE === 'point2D') {
      const [lo, hi] = [input.MIN || [], input.MAX || []];
      renderer.setValue(input.NAME, [clamp(0, lo[0], hi[0]), clamp(0, lo[1], hi[1])]);
    }
  }
  for (const [name, value] of Object.entries(job.values)) renderer.setValue(name, value);

  // The fixed clock. The renderer binds texture units from 0 at every draw, so the images are
  // bound again here, after its reset and before its buffers.
  let frame = 0;
  renderer.setDateUniforms = function fixedClock() {
    const time = frame * job.dt;
    this.setValue('TIME', time);
    this.setValue('TIMEDELTA', job.dt);
    this.setValue('FRAMEINDEX', frame);
    this.setValue('DATE', [job.date[0], job.date[1], job.date[2], (job.date[3] + time) % 86400]);
    for (const [name, image] of Object.entries(images)) this.setValue(name, image);
  };
  for (frame = 0; frame < job.frames; frame += 1) renderer.draw(canvas);
  const glError = gl.getError();

  const pixels = new Uint8Array(job.width * job.height * 4);
  gl.readPixels(0, 0, job.width, job.height, gl.RGBA, gl.UNSIGNED_BYTE, pixels);
  // GL's rows start at the bottom.
  const row = job.width * 4;
  const out = new Array(pixels.length);
  for (let y = 0; y < job.height; y += 1) {
    const from = (job.height - 1 - y) * row;
    for (let i = 0; i < row; i += 1) out[y * row + i] = pixels[from + i];
  }
  return { rgba: out, glError };
};
