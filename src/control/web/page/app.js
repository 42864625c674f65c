// indra's control surface. Builds its controls from the OSCQuery address tree (GET /), follows
// values through LISTEN, and writes them as binary OSC messages over the same WebSocket, so the
// show applies a browser's moves exactly as it applies a UDP controller's.
"use strict";

const access = document.querySelector('meta[name="indra-access"]').content;
const readOnly = access !== "control";

// ---- OSC 1.0 messages: the few types indra sends and takes ----

const encoder = new TextEncoder();
const decoder = new TextDecoder();

/** The bytes of `text` as an OSC string: NUL-terminated, padded to four bytes. */
function oscString(text) {
  const bytes = encoder.encode(text);
  const out = new Uint8Array((bytes.length + 4) & ~3);
  out.set(bytes);
  return out;
}

/** An OSC message to `address` with `args`, each `["f"|"i"|"s"|"T"|"F", value]`. */
function encodeMessage(address, args) {
  const tags = "," + args.map(([tag]) => tag).join("");
  const parts = [oscString(address), oscString(tags)];
  for (const [tag, value] of args) {
    if (tag === "f" || tag === "i") {
      const word = new DataView(new ArrayBuffer(4));
      if (tag === "f") word.setFloat32(0, value); else word.setInt32(0, value);
      parts.push(new Uint8Array(word.buffer));
    } else if (tag === "s") {
      parts.push(oscString(value));
    }
  }
  const out = new Uint8Array(parts.reduce((n, p) => n + p.length, 0));
  let at = 0;
  for (const p of parts) { out.set(p, at); at += p.length; }
  return out.buffer;
}

/** The address and argument values of an OSC message; `null` for anything else. */
function decodeMessage(buffer) {
  const bytes = new Uint8Array(buffer);
  const view = new DataView(buffer);
  let at = 0;
  const readString = () => {
    const end = bytes.indexOf(0, at);
    if (end < 0) throw new Error("unterminated string");
    const text = decoder.decode(bytes.subarray(at, end));
    at = (end + 4) & ~3;
    return text;
  };
  try {
    const address = readString();
    if (!address.startsWith("/")) return null;
    const tags = readString();
    const args = [];
    for (const tag of tags.slice(1)) {
      switch (tag) {
        case "f": args.push(view.getFloat32(at)); at += 4; break;
        case "i": args.push(view.getInt32(at)); at += 4; break;
        case "d": args.push(view.getFloat64(at)); at += 8; break;
        case "h": args.push(Number(view.getBigInt64(at))); at += 8; break;
        case "s": args.push(readString()); break;
        case "T": args.push(true); break;
        case "F": args.push(false); break;
        default: return null;
      }
    }
    return { address, args };
  } catch (e) {
    return null;
  }
}

// ---- The connection ----

const socketUrl = `${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/${location.search}`;
let socket = null;
/** Controls by address: each has `set(values)` and `el`. */
let controls = new Map();
/** The newest value heard for each address: a tree fetched while changes arrive may be older. */
const heard = new Map();
/** The values waiting to be sent, by address, flushed once per animation frame. */
const pending = new Map();

function setState(state, text) {
  document.body.dataset.state = state;
  document.getElementById("status").textContent = text;
}

/** Queues `args` for `address`; a drag sends at most one message per address per frame. */
function send(address, args) {
  if (readOnly) return;
  const first = pending.size === 0;
  pending.set(address, args);
  if (first) requestAnimationFrame(flush);
}

function flush() {
  if (!socket || socket.readyState !== WebSocket.OPEN) return;
  for (const [address, args] of pending) socket.send(encodeMessage(address, args));
  pending.clear();
}

/** Sends at once (a button press must not wait for, or merge into, a frame). */
function sendNow(address, args) {
  if (readOnly || !socket || socket.readyState !== WebSocket.OPEN) return;
  socket.send(encodeMessage(address, args));
}

function connect() {
  socket = new WebSocket(socketUrl);
  socket.binaryType = "arraybuffer";
  socket.onopen = () => {
    for (const [address, control] of controls) {
      if (control.listens) socket.send(JSON.stringify({ COMMAND: "LISTEN", DATA: address }));
    }
    setState("live", readOnly ? "live · read-only" : "live");
  };
  socket.onmessage = (event) => {
    if (typeof event.data === "string") {
      let said = {};
      try { said = JSON.parse(event.data); } catch (e) { return; }
      if (said.COMMAND === "PATH_CHANGED") load();
      return;
    }
    const message = decodeMessage(event.data);
    if (!message) return;
    heard.set(message.address, message.args);
    const control = controls.get(message.address);
    if (control && !control.held()) control.set(message.args);
  };
  socket.onclose = () => {
    setState("offline", "reconnecting…");
    setTimeout(connect, 1000);
  };
}

// ---- Building the surface from the tree ----

function el(tag, attributes = {}, ...children) {
  const node = document.createElement(tag);
  for (const [name, value] of Object.entries(attributes)) {
    if (name === "class") node.className = value;
    else if (name.startsWith("on")) node.addEventListener(name.slice(2), value);
    else node.setAttribute(name, value);
  }
  node.append(...children.filter((c) => c !== null && c !== undefined));
  return node;
}

const isLeaf = (node) => node && typeof node.TYPE === "string";
const childrenOf = (node) => Object.entries((node && node.CONTENTS) || {});
const rangeOf = (leaf, i) => (leaf.RANGE && leaf.RANGE[i]) || {};
const unitOf = (leaf) => (leaf.UNIT && leaf.UNIT[0]) || "";
const format = (x) => (Math.abs(x) >= 100 ? x.toFixed(0) : Math.abs(x) >= 10 ? x.toFixed(1) : x.toFixed(3));

/** Marks a control held while a finger or the mouse is on it: incoming values wait. */
function holdable(node) {
  let held = false;
  node.addEventListener("pointerdown", () => { held = true; });
  for (const end of ["pointerup", "pointercancel", "change", "blur"]) node.addEventListener(end, () => { held = false; });
  return () => held;
}

function labelled(name, leaf, input, readout) {
  return el("div", { class: "control", "data-path": leaf.FULL_PATH, title: leaf.DESCRIPTION || "" },
    el("label", {}, el("span", {}, name), readout), input);
}

/** A slider for one number (`f` or `i`). */
function numberControl(name, leaf, integer) {
  const r = rangeOf(leaf, 0);
  const bounded = r.MIN !== undefined && r.MAX !== undefined;
  const [lo, hi] = [r.MIN ?? 0, r.MAX ?? 1];
  // An unbounded number gets a field: a slider would pin it to a range it does not have.
  const input = bounded
    ? el("input", { type: "range", min: lo, max: hi, step: integer ? 1 : (hi - lo) / 1000 })
    : el("input", { type: "number", step: integer ? 1 : "any", inputmode: "decimal" });
  const readout = el("output");
  const show = (x) => { input.value = x; readout.textContent = (integer ? String(x) : format(x)) + (unitOf(leaf) ? " " + unitOf(leaf) : ""); };
  input.addEventListener("input", () => {
    const x = Number(input.value);
    show(x);
    send(leaf.FULL_PATH, [[integer ? "i" : "f", x]]);
  });
  return { el: labelled(name, leaf, input, readout), set: (v) => show(Number(v[0])), held: holdable(input), input };
}

function toggleControl(name, leaf) {
  const input = el("input", { type: "checkbox" });
  input.addEventListener("change", () => send(leaf.FULL_PATH, [[input.checked ? "T" : "F"]]));
  const node = el("label", { class: "control toggle", "data-path": leaf.FULL_PATH, title: leaf.DESCRIPTION || "" }, input, el("span", {}, name));
  return { el: node, set: (v) => { input.checked = Boolean(v[0]); }, held: () => false, input };
}

function triggerButton(text, address, extraClass = "") {
  const button = el("button", { type: "button", class: extraClass, "data-path": address }, text);
  button.addEventListener("click", () => {
    sendNow(address, []);
    button.classList.add("fired");
    setTimeout(() => button.classList.remove("fired"), 150);
  });
  return button;
}

function menuControl(name, leaf) {
  const input = el("select", {}, ...(rangeOf(leaf, 0).VALS || []).map((v) => el("option", { value: v }, v)));
  input.addEventListener("change", () => send(leaf.FULL_PATH, [["s", input.value]]));
  return { el: labelled(name, leaf, input, null), set: (v) => { input.value = v[0]; }, held: holdable(input), input };
}

function textControl(name, leaf) {
  const input = el("input", { type: "text", maxlength: 512 });
  input.addEventListener("change", () => send(leaf.FULL_PATH, [["s", input.value]]));
  let focused = false;
  input.addEventListener("focus", () => { focused = true; });
  input.addEventListener("blur", () => { focused = false; });
  return { el: labelled(name, leaf, input, null), set: (v) => { input.value = v[0]; }, held: () => focused, input };
}

const toHex = (x) => Math.round(Math.min(1, Math.max(0, x)) * 255).toString(16).padStart(2, "0");

function colorControl(name, leaf) {
  const input = el("input", { type: "color" });
  const alpha = el("input", { type: "range", min: 0, max: 1, step: 0.001, "aria-label": name + " alpha" });
  let value = [1, 1, 1, 1];
  const changed = () => {
    const hex = input.value;
    value = [1, 3, 5].map((i) => parseInt(hex.slice(i, i + 2), 16) / 255).concat(Number(alpha.value));
    send(leaf.FULL_PATH, value.map((x) => ["f", x]));
  };
  input.addEventListener("input", changed);
  alpha.addEventListener("input", changed);
  const set = (v) => {
    value = v.map(Number);
    input.value = "#" + value.slice(0, 3).map(toHex).join("");
    alpha.value = value[3] ?? 1;
  };
  const heldColor = holdable(input), heldAlpha = holdable(alpha);
  return { el: labelled(name, leaf, el("div", { class: "row" }, input, alpha), null), set, held: () => heldColor() || heldAlpha(), input };
}

/** A pad for a 2-D value: x right, y up, within the value's ranges. */
function xyControl(name, leaf) {
  const [rx, ry] = [rangeOf(leaf, 0), rangeOf(leaf, 1)];
  const [x0, x1, y0, y1] = [rx.MIN ?? 0, rx.MAX ?? 1, ry.MIN ?? 0, ry.MAX ?? 1];
  const dot = el("div", { class: "dot" });
  const pad = el("div", { class: "xy", role: "slider", "aria-label": name }, dot);
  const readout = el("output");
  const show = ([x, y]) => {
    dot.style.left = `${((x - x0) / (x1 - x0 || 1)) * 100}%`;
    dot.style.top = `${(1 - (y - y0) / (y1 - y0 || 1)) * 100}%`;
    readout.textContent = `${format(x)}, ${format(y)}`;
  };
  let held = false;
  const move = (event) => {
    const box = pad.getBoundingClientRect();
    const u = Math.min(1, Math.max(0, (event.clientX - box.left) / box.width));
    const v = Math.min(1, Math.max(0, 1 - (event.clientY - box.top) / box.height));
    const value = [x0 + u * (x1 - x0), y0 + v * (y1 - y0)];
    show(value);
    send(leaf.FULL_PATH, value.map((c) => ["f", c]));
  };
  if (!readOnly) {
    pad.addEventListener("pointerdown", (event) => { held = true; pad.setPointerCapture(event.pointerId); move(event); });
    pad.addEventListener("pointermove", (event) => { if (held) move(event); });
    for (const end of ["pointerup", "pointercancel"]) pad.addEventListener(end, () => { held = false; });
  }
  return { el: labelled(name, leaf, pad, readout), set: (v) => show(v.map(Number)), held: () => held };
}

/** One slider per component of a vector that is neither a colour nor a point. */
function vectorControl(name, leaf) {
  const parts = [...leaf.TYPE].map((_, i) => {
    const r = rangeOf(leaf, i);
    return el("input", { type: "range", min: r.MIN ?? 0, max: r.MAX ?? 1, step: ((r.MAX ?? 1) - (r.MIN ?? 0)) / 1000, "aria-label": `${name} ${"xyzw"[i]}` });
  });
  const readout = el("output");
  const show = (v) => { parts.forEach((p, i) => { p.value = v[i]; }); readout.textContent = v.map((x) => format(Number(x))).join(", "); };
  for (const p of parts) p.addEventListener("input", () => {
    const v = parts.map((q) => Number(q.value));
    show(v);
    send(leaf.FULL_PATH, v.map((x) => ["f", x]));
  });
  const helds = parts.map(holdable);
  return { el: labelled(name, leaf, el("div", { class: "body" }, ...parts), readout), set: show, held: () => helds.some((h) => h()) };
}

/** The control for a parameter leaf, by its type tag and WIDGET. */
function controlFor(name, leaf) {
  const type = leaf.TYPE;
  if (type === "f") return numberControl(name, leaf, false);
  if (type === "i") return numberControl(name, leaf, true);
  if (type === "T" || type === "F") return toggleControl(name, leaf);
  if (type === "s" && rangeOf(leaf, 0).VALS) return menuControl(name, leaf);
  if (type === "s") return textControl(name, leaf);
  if (leaf.WIDGET === "color") return colorControl(name, leaf);
  if (leaf.WIDGET === "xy") return xyControl(name, leaf);
  if (/^f{2,4}$/.test(type)) return vectorControl(name, leaf);
  return null;
}

/** Registers `control` for `leaf` and returns its element. */
function adopt(leaf, control) {
  control.listens = (leaf.ACCESS & 1) === 1;
  const value = heard.get(leaf.FULL_PATH) || leaf.VALUE;
  if (Array.isArray(value) && value.length) control.set(value);
  controls.set(leaf.FULL_PATH, control);
  return control.el;
}

function group(title, subtitle, klass, ...body) {
  return el("details", { class: `group ${klass}`, open: "" },
    el("summary", {}, el("span", {}, title), subtitle ? el("small", {}, subtitle) : null),
    el("div", { class: "body" }, ...body));
}

/** A clip's name from its trigger's description ("play red on layer 1"). */
const clipName = (leaf, fallback) => (/^play (.+) on /.exec(leaf.DESCRIPTION || "") || [])[1] || fallback;

/**
 * An effect chain (the `fx` of a layer or of the master): each effect in order with buttons that
 * move it up or down or remove it, and a menu that adds one from the library. An effect's bypass,
 * mix and own parameters are in its own group.
 */
function chainRow(title, fx) {
  const c = (fx && fx.CONTENTS) || {};
  if (!c.add) return null;
  const button = (text, leaf, args, label) => {
    const b = el("button", { type: "button", "data-path": leaf.FULL_PATH, "aria-label": label }, text);
    b.addEventListener("click", () => sendNow(leaf.FULL_PATH, args));
    return b;
  };
  const effects = childrenOf(fx).filter(([k]) => /^[0-9]+$/.test(k)).sort((a, b) => a[0] - b[0]);
  const items = effects.map(([k, effect]) => {
    const n = Number(k);
    const file = effect.CONTENTS && effect.CONTENTS.file && effect.CONTENTS.file.VALUE;
    const name = file ? String(file[0]).replace(/^.*\//, "").replace(/\.fs$/, "") : (effect.DESCRIPTION || `effect ${k}`);
    return el("div", { class: "row" }, el("span", {}, `${k} ${name}`),
      n > 1 && c.move ? button("▲", c.move, [["i", n], ["i", n - 1]], `move ${name} up`) : null,
      n < effects.length && c.move ? button("▼", c.move, [["i", n], ["i", n + 1]], `move ${name} down`) : null,
      c.remove ? button("✕", c.remove, [["i", n]], `remove ${name}`) : null);
  });
  const names = rangeOf(c.add, 0).VALS || [];
  const add = el("select", { "data-path": c.add.FULL_PATH, "aria-label": `add an effect to ${title}` },
    el("option", { value: "" }, "add an effect…"), ...names.map((v) => el("option", { value: v }, v)));
  add.addEventListener("change", () => { if (add.value) sendNow(c.add.FULL_PATH, [["s", add.value]]); add.value = ""; });
  return el("div", { class: "chain" }, el("h4", {}, `effects · ${title}`), ...items, add);
}

/** The show: a row per layer (its clips, its fader and blend), the columns, the cue list. */
function showGroup(root) {
  const layers = root.layer;
  if (!layers) return null;
  const rows = childrenOf(layers).map(([n, layer]) => {
    const contents = layer.CONTENTS || {};
    const clips = childrenOf(contents.clip).map(([m, clip]) => {
      const leaf = clip.CONTENTS && clip.CONTENTS.connect;
      if (!leaf) return null;
      const name = clipName(leaf, `clip ${m}`);
      // The tree holds the parameters of the clips on screen: those are the ones playing.
      return triggerButton(name, leaf.FULL_PATH, root[name] ? "playing" : "");
    });
    const clear = contents.clear ? triggerButton("clear", contents.clear.FULL_PATH) : null;
    const params = Object.entries(contents).filter(([, leaf]) => isLeaf(leaf) && leaf.ACCESS & 1)
      .map(([name, leaf]) => { const c = controlFor(name, leaf); return c && adopt(leaf, c); });
    const name = ((contents.clear && contents.clear.DESCRIPTION) || "").replace(/^empty /, "") || `layer ${n}`;
    return el("div", { class: "layer" }, el("h3", {}, name),
      el("div", { class: "grid" }, ...clips, clear), ...params, chainRow(name, contents.fx));
  });
  rows.push(chainRow("master", root.master && root.master.CONTENTS && root.master.CONTENTS.fx));
  const columns = childrenOf(root.column).map(([n, column]) => {
    const leaf = column.CONTENTS && column.CONTENTS.connect;
    return leaf ? triggerButton((leaf.DESCRIPTION || `column ${n}`).replace(/^play column /, "▶ "), leaf.FULL_PATH) : null;
  });
  const cue = root.cue && root.cue.CONTENTS;
  let cues = null;
  if (cue) {
    const goto = cue.goto && el("select", { "data-path": cue.goto.FULL_PATH, "aria-label": "go to cue" },
      el("option", { value: "" }, "go to cue…"), ...(rangeOf(cue.goto, 0).VALS || []).map((v) => el("option", { value: v }, v)));
    if (goto) goto.addEventListener("change", () => { if (goto.value) sendNow(cue.goto.FULL_PATH, [["s", goto.value]]); goto.value = ""; });
    cues = el("div", { class: "row" },
      cue.back ? triggerButton("◀ back", cue.back.FULL_PATH) : null,
      cue.go ? triggerButton("GO", cue.go.FULL_PATH, "go") : null, goto);
  }
  return group("Show", null, "show", cues, columns.length ? el("div", { class: "grid" }, ...columns) : null, ...rows);
}

/** Tempo (BPM and tap) and presets (recall with a morph time, save). */
function engineGroup(root) {
  const tempo = root.tempo && root.tempo.CONTENTS;
  const preset = root.preset && root.preset.CONTENTS;
  const parts = [];
  if (tempo && tempo.bpm) {
    const bpm = numberControl("tempo", tempo.bpm, false);
    parts.push(adopt(tempo.bpm, bpm));
  }
  if (tempo && tempo.tap) parts.push(el("div", { class: "row" }, triggerButton("tap tempo", tempo.tap.FULL_PATH)));
  if (preset && preset.recall) {
    const names = rangeOf(preset.recall, 0).VALS || [];
    const menu = el("select", { "aria-label": "preset" }, ...names.map((v) => el("option", { value: v }, v)));
    const morph = el("input", { type: "number", min: 0, max: 60, step: 0.5, value: 0, "aria-label": "morph seconds" });
    const recall = el("button", { type: "button", "data-path": preset.recall.FULL_PATH }, "recall");
    recall.addEventListener("click", () => {
      if (menu.value) sendNow(preset.recall.FULL_PATH, [["s", menu.value], ["f", Math.max(0, Number(morph.value) || 0)]]);
    });
    parts.push(el("div", { class: "control" }, el("label", {}, el("span", {}, "preset · morph seconds")),
      el("div", { class: "row" }, menu, morph, recall)));
  }
  if (preset && preset.save) {
    const name = el("input", { type: "text", placeholder: "new preset name", maxlength: 64 });
    const save = el("button", { type: "button", "data-path": preset.save.FULL_PATH }, "save");
    save.addEventListener("click", () => { if (name.value.trim()) sendNow(preset.save.FULL_PATH, [["s", name.value.trim()]]); });
    parts.push(el("div", { class: "row" }, name, save));
  }
  return parts.length ? group("Tempo & presets", null, "engine", ...parts) : null;
}

/** Every container holding parameters, as one group each, in tree order. */
function nodeGroups(contents, prefix, out) {
  const leaves = [];
  for (const [name, child] of Object.entries(contents)) {
    if (isLeaf(child)) {
      // A chain's edits have their own row in the show group.
      if (prefix.endsWith("/fx") || prefix === "fx") continue;
      if (!(child.ACCESS & 1) && child.TYPE === "I") leaves.push(triggerButton(name, child.FULL_PATH));
      else { const c = controlFor(name, child); if (c) leaves.push(adopt(child, c)); }
    } else if (child && child.CONTENTS) {
      nodeGroups(child.CONTENTS, prefix ? `${prefix}/${name}` : name, out);
    }
  }
  if (leaves.length && prefix) {
    const node = out.tree && out.tree[prefix];
    out.groups.push(group(prefix, (node && node.DESCRIPTION) || null, "node", ...leaves));
  }
}

/** The containers of `root` by their path under /indra (for their descriptions). */
function containers(contents, prefix, out) {
  for (const [name, child] of Object.entries(contents)) {
    if (child && child.CONTENTS && !isLeaf(child)) {
      const path = prefix ? `${prefix}/${name}` : name;
      out[path] = child;
      containers(child.CONTENTS, path, out);
    }
  }
  return out;
}

function build(tree) {
  const indra = tree.CONTENTS && tree.CONTENTS.indra;
  if (!indra) return;
  document.getElementById("title").textContent = indra.DESCRIPTION || "indra";
  document.title = `${indra.DESCRIPTION || "indra"} · indra`;
  controls = new Map();
  const root = indra.CONTENTS || {};
  const groups = [showGroup(root), engineGroup(root)].filter(Boolean);
  // The show's and the engine's addresses have their own groups above.
  const rest = Object.fromEntries(Object.entries(root).filter(([name]) => !["layer", "column", "cue", "preset", "tempo"].includes(name)));
  const out = { groups: [], tree: containers(rest, "", {}) };
  nodeGroups(rest, "", out);
  const surface = document.getElementById("surface");
  surface.replaceChildren(...groups, ...out.groups);
  // A read-only surface shows every control, none of them usable.
  if (readOnly) surface.querySelectorAll("input, select, button").forEach((c) => { c.disabled = true; });
}

/** Fetches the tree and rebuilds; LISTENs to every value once connected. */
async function load() {
  let tree = null;
  while (!tree) {
    try {
      const reply = await fetch("/", { headers: { Accept: "application/json" }, cache: "no-store" });
      if (reply.ok) tree = await reply.json();
    } catch (e) { /* the show is not up yet */ }
    if (!tree) await new Promise((done) => setTimeout(done, 500));
  }
  build(tree);
  if (socket && socket.readyState === WebSocket.OPEN) socket.onopen();
  else if (!socket) connect();
}

load();
