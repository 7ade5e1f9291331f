// The experiment report's image viewer (xtask/src/experiments/viewer): per scene the reference
// and each strategy at each budget, flip (A/B) or swipe, zoom and pan with sharp pixels, an
// exposure control applied to linear values, per-pixel relMSE maps computed here, and the
// harness's HDR-ꟻLIP maps (magma PNGs made from the full-precision renders).
// Images come as RGBE split PNGs in data URIs (viewer/encode.rs): a data URI does not taint a
// canvas under file://, so the linear values can be read back.
"use strict";
const MLV = (() => {
  const scenes = [];
  const st = { scene: 0, budget: 0, a: null, b: "reference", mode: "flip", view: "image",
               stops: 0, showB: false, zoom: 1, tx: 0, ty: 0, split: 0.5 };
  const decoded = new Map();
  const $ = (id) => document.getElementById(id);

  // Linear RGB of an RGBE split PNG (mantissas above, exponents below): (m + 0.5)·2^(e − 136).
  function decode(uri, w, h) {
    if (decoded.has(uri)) return decoded.get(uri);
    const p = new Promise((ok, fail) => {
      const img = new Image();
      img.onload = () => {
        const c = document.createElement("canvas");
        c.width = w; c.height = 2 * h;
        const g = c.getContext("2d", { willReadFrequently: true });
        g.drawImage(img, 0, 0);
        const d = g.getImageData(0, 0, w, 2 * h).data;
        const n = w * h, rgb = new Float32Array(3 * n);
        for (let i = 0; i < n; i++) {
          const e = d[4 * (n + i)];
          if (e === 0) continue;
          const f = Math.pow(2, e - 136);
          for (let k = 0; k < 3; k++) rgb[3 * i + k] = (d[4 * i + k] + 0.5) * f;
        }
        ok(rgb);
      };
      img.onerror = () => fail(new Error("cannot decode an image"));
      img.src = uri;
    });
    decoded.set(uri, p);
    return p;
  }

  // A grey PNG, 255 where no camera ray sees a light: true there.
  function decodeMask(uri, w, h) {
    if (!uri) return Promise.resolve(null);
    const key = "mask:" + uri;
    if (decoded.has(key)) return decoded.get(key);
    const p = new Promise((ok) => {
      const img = new Image();
      img.onload = () => {
        const c = document.createElement("canvas");
        c.width = w; c.height = h;
        const g = c.getContext("2d", { willReadFrequently: true });
        g.drawImage(img, 0, 0);
        const d = g.getImageData(0, 0, w, h).data, m = new Uint8Array(w * h);
        for (let i = 0; i < w * h; i++) m[i] = d[4 * i] > 127 ? 1 : 0;
        ok(m);
      };
      img.onerror = () => ok(null);
      img.src = uri;
    });
    decoded.set(key, p);
    return p;
  }

  // An ordinary PNG (a ꟻLIP map) as an image element, once.
  function loadImage(uri) {
    const key = "img:" + uri;
    if (decoded.has(key)) return decoded.get(key);
    const p = new Promise((ok) => {
      const img = new Image();
      img.onload = () => ok(img);
      img.onerror = () => ok(null);
      img.src = uri;
    });
    decoded.set(key, p);
    return p;
  }

  const srgb = (c) => {
    c = c > 0 ? (c < 1 ? c : 1) : 0;
    return 255 * (c <= 0.0031308 ? 12.92 * c : 1.055 * Math.pow(c, 1 / 2.4) - 0.055) + 0.5;
  };

  // Log scale 1e-4 (dark blue) → 10 (yellow); grey where the camera sees a light (as the
  // harness's error-maps/).
  const STOPS = [[0.07, 0.02, 0.25], [0.25, 0.15, 0.55], [0.15, 0.55, 0.55], [0.45, 0.8, 0.3], [0.99, 0.9, 0.15]];
  function errorColour(e, out, o) {
    const t = Math.min(Math.max((Math.log10(Math.max(e, 1e-12)) + 4) / 5, 0), 1) * 4;
    const i = Math.min(Math.floor(t), 3), f = t - i;
    for (let k = 0; k < 3; k++) out[o + k] = (STOPS[i][k] * (1 - f) + STOPS[i + 1][k] * f) * 255;
  }

  function item(scene, name) {
    if (name === "reference") return scene.reference;
    const b = scene.budgets[st.budget];
    return scene.cells.find((c) => c.strategy === name && c.budget === b) || null;
  }

  async function paint(canvas, scene, name) {
    const it = item(scene, name), w = scene.width, h = scene.height;
    canvas.width = w; canvas.height = h;
    const g = canvas.getContext("2d");
    const out = g.createImageData(w, h), o = out.data;
    if (!it || !it.image) { g.fillStyle = "#555"; g.fillRect(0, 0, w, h); return; }
    if (st.view === "flip" && name !== "reference") {
      // a grey PNG of magma palette indices (viewer/mod.rs): colour it
      const img = it.flip_map ? await loadImage(it.flip_map) : null;
      if (!img) { g.fillStyle = "#555"; g.fillRect(0, 0, w, h); return; }
      g.drawImage(img, 0, 0, w, h);
      const d = g.getImageData(0, 0, w, h).data, pal = scene.flip_palette;
      for (let i = 0; i < w * h; i++) {
        const k = 3 * d[4 * i];
        o[4 * i] = pal[k]; o[4 * i + 1] = pal[k + 1]; o[4 * i + 2] = pal[k + 2]; o[4 * i + 3] = 255;
      }
      g.putImageData(out, 0, 0);
      return;
    }
    const px = await decode(it.image, w, h);
    if (st.view === "error" && name !== "reference" && scene.reference) {
      const ref = await decode(scene.reference.image, w, h);
      const m1 = await decodeMask(scene.reference.unlit, w, h), m2 = await decodeMask(it.unlit, w, h);
      for (let i = 0; i < w * h; i++) {
        const lit = (m1 && !m1[i]) || (m2 && !m2[i]);
        if (lit) { o[4 * i] = o[4 * i + 1] = o[4 * i + 2] = 90; }
        else {
          let e = 0;
          for (let k = 0; k < 3; k++) {
            const x = px[3 * i + k], r = ref[3 * i + k];
            e += (x - r) * (x - r) / (r * r + 0.01);
          }
          errorColour(e / 3, o, 4 * i);
        }
        o[4 * i + 3] = 255;
      }
    } else {
      const s = scene.exposure * Math.pow(2, st.stops);
      for (let i = 0; i < w * h; i++) {
        for (let k = 0; k < 3; k++) o[4 * i + k] = srgb(px[3 * i + k] * s);
        o[4 * i + 3] = 255;
      }
    }
    g.putImageData(out, 0, 0);
  }

  function caption(scene, name) {
    const it = item(scene, name);
    if (name === "reference") return scene.reference ? "reference: " + scene.reference.caption : "reference (not on this machine)";
    if (!it) return name + ": no cell";
    let s = name + ": relMSE " + it.rel_mse.toExponential(2) +
      (it.flip != null ? ", ꟻLIP " + it.flip.toFixed(4) : "") + ", " + it.spp + " spp, " + it.seconds.toFixed(2) + " s, seed " + it.seed;
    if (!it.image) s += " (render not on this machine)";
    return s;
  }

  function transform() {
    $("layer").style.transform = "translate(" + st.tx + "px," + st.ty + "px) scale(" + st.zoom + ")";
    const stage = $("stage"), scene = scenes[st.scene];
    const swipe = st.mode === "swipe";
    const cb = $("canvasB");
    if (swipe) {
      // the split is a stage x position; in image pixels it is (x − tx) / zoom
      const x = st.split * stage.clientWidth, ix = (x - st.tx) / st.zoom;
      const pct = Math.min(Math.max(ix / scene.width, 0), 1) * 100;
      cb.style.display = "block";
      cb.style.clipPath = "inset(0 0 0 " + pct + "%)";
      $("split").style.display = "block";
      $("split").style.left = x + "px";
    } else {
      cb.style.clipPath = "none";
      cb.style.display = st.showB ? "block" : "none";
      $("split").style.display = "none";
    }
  }

  function fit() {
    const scene = scenes[st.scene], stage = $("stage");
    const z = Math.max(1, Math.floor(Math.min(stage.clientWidth / scene.width, stage.clientHeight / scene.height)));
    st.zoom = z;
    st.tx = Math.round((stage.clientWidth - z * scene.width) / 2);
    st.ty = Math.round((stage.clientHeight - z * scene.height) / 2);
    transform();
  }

  function button(parent, text, on, click, disabled, title) {
    const b = document.createElement("button");
    b.textContent = text;
    if (on) b.classList.add("on");
    if (disabled) b.disabled = true;
    if (title) b.title = title;
    b.onclick = click;
    parent.appendChild(b);
    return b;
  }

  function names(scene) { return ["reference"].concat(scene.strategies); }

  async function update() {
    const scene = scenes[st.scene];
    const bars = $("bars");
    bars.textContent = "";
    const row = (label) => {
      const d = document.createElement("div"); d.className = "bar";
      const n = document.createElement("span"); n.className = "name"; n.textContent = label;
      d.appendChild(n); bars.appendChild(d); return d;
    };
    const r1 = row("scene");
    scenes.forEach((s, i) => button(r1, s.label, i === st.scene, () => { st.scene = i; st.budget = 0; pick(); fit(); update(); }));
    const r2 = row("budget");
    scene.budgets.forEach((b, i) => button(r2, b, i === st.budget, () => { st.budget = i; update(); }));
    for (const [label, key] of [["A (1–9)", "a"], ["B (⇧1–9)", "b"]]) {
      const r = row(label);
      names(scene).forEach((n, i) => {
        const it = item(scene, n);
        button(r, (i < 10 ? i + " " : "") + n, st[key] === n, () => { st[key] = n; update(); },
               !it || !it.image, it && !it.image ? "render not on this machine" : "");
      });
    }
    const r5 = row("view");
    button(r5, "flip A/B (space)", st.mode === "flip", () => { st.mode = "flip"; update(); });
    button(r5, "swipe (s)", st.mode === "swipe", () => { st.mode = "swipe"; update(); });
    button(r5, "image", st.view === "image", () => { st.view = "image"; update(); });
    button(r5, "relMSE map (e)", st.view === "error", () => { st.view = "error"; update(); }, !scene.reference);
    const anyFlip = scene.cells.some((c) => c.budget === scene.budgets[st.budget] && c.flip_map);
    button(r5, "ꟻLIP map (l)", st.view === "flip", () => { st.view = "flip"; update(); }, !anyFlip,
           anyFlip ? "" : "no ꟻLIP maps: the renders are not on this machine");
    button(r5, "fit (f)", false, fit);
    const r6 = row("exposure");
    const range = document.createElement("input");
    range.type = "range"; range.min = -10; range.max = 10; range.step = 0.25; range.value = st.stops;
    range.oninput = () => { st.stops = parseFloat(range.value); update(); };
    r6.appendChild(range);
    const ev = document.createElement("span");
    ev.textContent = (st.stops >= 0 ? "+" : "") + st.stops.toFixed(2) + " stops over the reference's auto exposure (−/+)";
    r6.appendChild(ev);
    button(r6, "0", false, () => { st.stops = 0; update(); });

    await Promise.all([paint($("canvasA"), scene, st.a), paint($("canvasB"), scene, st.b)]);
    const showing = st.mode === "swipe" ? "left A, right B" : (st.showB ? "showing B" : "showing A");
    $("tagA").textContent = st.mode === "swipe" ? "A: " + st.a : (st.showB ? "B: " + st.b : "A: " + st.a);
    $("tagB").textContent = st.mode === "swipe" ? "B: " + st.b : "";
    $("tagB").style.display = st.mode === "swipe" ? "block" : "none";
    $("info").textContent = showing + " — A = " + caption(scene, st.a) + " | B = " + caption(scene, st.b) +
      (st.view === "error" ? " | per-pixel relMSE against the reference (from the previews, ≈1 % precision)" : "") +
      (st.view === "flip" ? " | HDR-ꟻLIP against the reference (the harness's, from the full-precision renders)" : "");
    $("note").textContent = scene.cells.some((c) => c.image) ? "" :
      "The cells' renders (results/<experiment>/renders/, not committed) were not on the machine that wrote this page: only the reference, the harness's error maps, the tables and the plots are shown. Rerun the experiment to see every render.";
    maps(scene);
    transform();
    document.body.dataset.ready = scene.label + ":" + st.a + ":" + st.b + ":" + st.view + ":" + (st.showB ? "B" : "A");
  }

  function maps(scene) {
    const lists = [["maps", "mapsTitle", scene.error_maps, "relMSE maps"],
                   ["flipMaps", "flipMapsTitle", scene.flip_maps || [], "HDR-ꟻLIP maps"]];
    for (const [box, title, list, what] of lists) {
      const m = $(box);
      m.textContent = "";
      $(title).textContent = list.length
        ? what + " of " + scene.label + " computed by the harness from the full-precision renders (" + scene.error_maps_budget + ")"
        : "";
      for (const e of list) {
        const f = document.createElement("figure");
        const img = document.createElement("img");
        img.className = "px"; img.src = e.src; img.alt = e.strategy;
        const c = document.createElement("figcaption"); c.textContent = e.strategy;
        f.appendChild(img); f.appendChild(c); m.appendChild(f);
      }
    }
  }

  // The default A: the last strategy with an image, else the reference.
  function pick() {
    const scene = scenes[st.scene];
    const withImage = scene.strategies.filter((n) => { const it = item(scene, n); return it && it.image; });
    st.a = withImage.length ? withImage[withImage.length - 1] : "reference";
    st.b = "reference";
    st.showB = false;
  }

  function events() {
    const stage = $("stage");
    let drag = null;
    stage.addEventListener("mousedown", (e) => { drag = { x: e.clientX, y: e.clientY }; stage.classList.add("dragging"); });
    window.addEventListener("mouseup", () => { drag = null; stage.classList.remove("dragging"); });
    stage.addEventListener("mousemove", (e) => {
      const r = stage.getBoundingClientRect();
      if (drag) {
        st.tx += e.clientX - drag.x; st.ty += e.clientY - drag.y;
        drag = { x: e.clientX, y: e.clientY };
      } else if (st.mode === "swipe") {
        st.split = (e.clientX - r.left) / r.width;
      }
      transform();
    });
    stage.addEventListener("wheel", (e) => {
      e.preventDefault();
      const r = stage.getBoundingClientRect(), mx = e.clientX - r.left, my = e.clientY - r.top;
      const f = e.deltaY < 0 ? 1.25 : 0.8, z = Math.min(Math.max(st.zoom * f, 0.25), 128);
      st.tx = mx - (mx - st.tx) * (z / st.zoom);
      st.ty = my - (my - st.ty) * (z / st.zoom);
      st.zoom = z;
      transform();
    }, { passive: false });
    stage.addEventListener("dblclick", fit);
    window.addEventListener("keydown", (e) => {
      if (e.target.tagName === "INPUT") return;
      const scene = scenes[st.scene], list = names(scene);
      const digit = e.code.startsWith("Digit") ? parseInt(e.code.slice(5), 10) : NaN;
      if (!isNaN(digit) && digit < list.length) {
        const it = item(scene, list[digit]);
        if (it && it.image) { if (e.shiftKey) st.b = list[digit]; else st.a = list[digit]; }
      } else if (e.key === " ") { e.preventDefault(); st.showB = !st.showB; transform(); update(); return; }
      else if (e.key === "s") st.mode = st.mode === "swipe" ? "flip" : "swipe";
      else if (e.key === "e") st.view = st.view === "error" ? "image" : "error";
      else if (e.key === "l") st.view = st.view === "flip" ? "image" : "flip";
      else if (e.key === "f") { fit(); return; }
      else if (e.key === "-") st.stops -= 0.5;
      else if (e.key === "+" || e.key === "=") st.stops += 0.5;
      else return;
      update();
    });
  }

  return {
    scene(s) { scenes.push(s); },
    start() {
      if (!scenes.length) { $("note").textContent = "No scene data (viewer/*.js) was found."; return; }
      const q = new URLSearchParams(location.search);
      pick();
      // ?scene=N&a=NAME&b=NAME&view=error&mode=swipe&flip=1: a state to link to (and to test)
      if (q.has("scene")) { st.scene = Math.min(parseInt(q.get("scene"), 10) || 0, scenes.length - 1); pick(); }
      for (const k of ["a", "b", "view", "mode"]) if (q.has(k)) st[k] = q.get(k);
      if (q.has("budget")) st.budget = parseInt(q.get("budget"), 10) || 0;
      if (q.get("flip") === "1") st.showB = true;
      events();
      fit();
      update();
    },
  };
})();
