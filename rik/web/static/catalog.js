// The catalog pages of rik serve: handle and base-unit cards from /api/catalog/*, filters (type, size, finish,
// split, the base unit a handle fits, text) applied in the page and kept in the address's query (reload and
// back/forward restore them), thumbnails at their own or at one common scale, a side panel with one entry (and its
// 3D view, viewer3d.js), the resistance presets' numbers, and a pairing picker that links to /teleop/<variant id>
// (the variant ids come from the server, made by rik.registry.ids). Plain JavaScript, no build step.
"use strict";

const TYPE_LABEL = {knob: "Knob", two_point: "Two-point", finger_pull: "Finger pull"};
const state = {handles: [], bases: [], presets: {}, robots: {default: "hand-e", robots: []}};
const TABS = ["handles", "bases", "presets"];
const $ = (selector) => document.querySelector(selector);
const path = (id) => id.split("/").map(encodeURIComponent).join("/");

function el(tag, attrs = {}, ...children) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs)) {
    if (value === null || value === undefined) continue;
    if (key === "class") node.className = value;
    else if (key.startsWith("on")) node.addEventListener(key.slice(2), value);
    else node.setAttribute(key, value);
  }
  for (const child of children.flat()) {
    if (child !== null && child !== undefined) node.append(child instanceof Node ? child : String(child));
  }
  return node;
}

async function getJSON(url) {
  const response = await fetch(url);
  const body = await response.json();
  if (!response.ok) throw new Error(body.detail || response.statusText);
  return body;
}

function fmt(value, digits = 2) {
  if (value === null || value === undefined) return "–";
  if (typeof value === "boolean") return value ? "yes" : "no";
  return Number.isInteger(value) ? String(value) : value.toFixed(digits);
}

function num(value) { // a measured number to 3 significant digits, without trailing zeros
  return value === null || value === undefined ? "–" : String(Number(value.toPrecision(3)));
}

function table(rows, headers = null) {
  const head = headers ? el("thead", {}, el("tr", {}, headers.map((h, i) => el("th", {class: i ? "num" : ""}, h))))
    : null;
  return el("table", {}, head, el("tbody", {}, rows.map(
    (cells) => el("tr", {}, cells.map((c, i) => el(i ? "td" : "th", {class: i ? "num" : ""}, c))))));
}

// ---- handles grid and filters ---------------------------------------------------------------------------
function handleCard(h) {
  const card = el("a", {class: "card handle", href: `/catalog/handle/${path(h.id)}`, "data-id": h.id,
                        onclick: (e) => { e.preventDefault(); openHandle(h.id, true).catch(fail); }},
    el("div", {class: "thumb-box"},
       el("img", {class: "thumb", src: `/catalog/img/${path(h.id)}/thumbnail.png`, alt: `thumbnail of ${h.id}`,
                  width: 120, height: 120})),
    el("div", {class: "title"}, h.id),
    el("div", {class: "meta"}, `${TYPE_LABEL[h.type]} · ${fmt(h.dimensions_mm.length, 0)} mm`),
    el("div", {class: "meta"}, el("span", {class: "swatch", style: `background:${h.finish_color}`}), h.finish_name));
  card.handle = h;
  return card;
}

function sizeFilter() {
  const min = parseFloat($("#f-min").value);
  const max = parseFloat($("#f-max").value);
  return [Number.isNaN(min) ? -Infinity : min, Number.isNaN(max) ? Infinity : max];
}

// ---- filters in the address: /catalog?type=knob&split=val&base=...&scale=common ------------------------------
const FILTERS = {type: "#f-type", size: "#f-size", min: "#f-min", max: "#f-max", finish: "#f-finish",
                 split: "#f-split", base: "#f-base", q: "#f-text"};

function filterQuery() {
  const query = new URLSearchParams();
  for (const [key, selector] of Object.entries(FILTERS)) if ($(selector).value) query.set(key, $(selector).value);
  if ($("#f-scale").checked) query.set("scale", "common");
  const text = query.toString();
  return text ? `?${text}` : "";
}

function restoreFilters() {
  const query = new URLSearchParams(location.search);
  for (const [key, selector] of Object.entries(FILTERS)) {
    $(selector).value = query.get(key) || "";
    if ($(selector).tagName === "SELECT" && $(selector).selectedIndex < 0) $(selector).value = ""; // not an option
  }
  $("#f-scale").checked = query.get("scale") === "common";
}

// Common scale: a thumbnail frames its handle's bounding box (its largest dimension fills the picture), so drawing
// each at (largest dimension / the catalog's largest) of the box puts every handle at about one mm per pixel.
function applyScale() {
  const common = $("#f-scale").checked;
  const largest = Math.max(...state.handles.map((h) => h.extent_mm));
  for (const card of document.querySelectorAll("#handle-grid .card")) {
    const side = common ? Math.max(120 * card.handle.extent_mm / largest, 4) : 120;
    card.querySelector("img").style.width = card.querySelector("img").style.height = `${side.toFixed(1)}px`;
  }
  $("#scale-note").hidden = !common;
  $("#scale-note").textContent = `Common scale: each thumbnail is drawn in proportion to its handle's largest `
    + `dimension, the largest (${fmt(largest, 0)} mm) filling 120 px: about ${fmt(largest / 120, 1)} mm per pixel.`;
}

function applyFilters() {
  const type = $("#f-type").value;
  const finish = $("#f-finish").value;
  const split = $("#f-split").value;
  const base = $("#f-base").value;
  const [min, max] = sizeFilter();
  const words = $("#f-text").value.toLowerCase().split(/\s+/).filter(Boolean);
  let shown = 0;
  for (const card of document.querySelectorAll("#handle-grid .card")) {
    const h = card.handle;
    const text = [h.id, h.design_name, h.finish, h.finish_name, h.type, TYPE_LABEL[h.type], h.split,
                  h.display.mount].join(" ").toLowerCase();
    const length = h.dimensions_mm.length;
    const visible = (!type || h.type === type) && (!finish || h.finish === finish) && (!split || h.split === split)
      && (!base || h.fit_bases.includes(base)) && length >= min && length <= max && words.every((w) => text.includes(w));
    card.hidden = !visible;
    shown += visible;
  }
  $("#count").textContent = `${shown} of ${state.handles.length} handles`;
  applyScale();
  const address = location.pathname + filterQuery() + location.hash;
  if (address !== location.pathname + location.search + location.hash) history.replaceState(history.state, "", address);
}

function setupFilters(finishes) {
  const counts = {};
  for (const h of state.handles) counts[h.type] = (counts[h.type] || 0) + 1;
  for (const [type, label] of Object.entries(TYPE_LABEL)) {
    if (counts[type]) $("#f-type").append(el("option", {value: type}, `${label} (${counts[type]})`));
  }
  const used = new Set(state.handles.map((h) => h.finish));
  for (const f of finishes.filter((f) => used.has(f.id))) {
    const n = state.handles.filter((h) => h.finish === f.id).length;
    $("#f-finish").append(el("option", {value: f.id}, `${f.name} (${n})`));
  }
  for (const split of ["train", "val", "test"]) {
    const n = state.handles.filter((h) => h.split === split).length;
    if (n) $("#f-split").append(el("option", {value: split}, `${split} (${n})`));
  }
  for (const b of state.bases) $("#f-base").append(el("option", {value: b.id}, `${b.id} (${b.fits})`));
  $("#f-size").addEventListener("change", () => {
    const [lo, hi] = $("#f-size").value.split("-");
    $("#f-min").value = lo || "";
    $("#f-max").value = hi || "";
    applyFilters();
  });
  for (const id of ["#f-type", "#f-finish", "#f-split", "#f-base", "#f-scale"]) $(id).addEventListener("change", applyFilters);
  for (const id of ["#f-min", "#f-max", "#f-text"]) $(id).addEventListener("input", () => {
    if (id !== "#f-text") $("#f-size").value = "";
    applyFilters();
  });
  $("#f-reset").addEventListener("click", () => {
    $("#filters").reset();
    applyFilters();
  });
}

// ---- pairing picker ---------------------------------------------------------------------------------------
function picker(pairings, noun, grouped) {
  // pairings: [{id, label, type, variants: {preset: variant id}}] from the server (only pairings that fit)
  if (!pairings.length) return el("p", {class: "note"}, `No ${noun} fits this entry.`);
  const other = el("select", {id: "pair-other", "aria-label": noun});
  const groups = {};
  for (const [i, p] of pairings.entries()) {
    const option = el("option", {value: i}, p.label === p.id ? p.id : `${p.id} (${p.label})`);
    if (grouped) (groups[p.type] ||= el("optgroup", {label: TYPE_LABEL[p.type] || p.type})).append(option);
    else other.append(option);
  }
  other.append(...Object.values(groups));
  const preset = el("select", {id: "pair-preset", "aria-label": "resistance preset"});
  // the robot that opens it: the station at /teleop/<variant>?robot=<id> (none: the server's --robot)
  const robot = el("select", {id: "pair-robot", "aria-label": "robot"},
                   ...state.robots.robots.map((r) => el("option", {value: r.id}, `${r.id} (${r.name})`)));
  robot.value = pickedRobot || state.robots.default;
  const link = el("a", {id: "teleop-link", class: "go"}, "Build and teleoperate");
  const shownId = el("code", {id: "variant-id"});
  const numbers = el("p", {id: "preset-numbers", class: "note"});
  // the chosen variant in 3D, when it is built (the server answers one line naming the command otherwise)
  const viewer = el("div", {id: "viewer-variant", class: "viewer3d", hidden: ""});
  const show3d = el("button", {type: "button", id: "variant-3d", onclick: () => {
    viewer.hidden = false;
    view3d(viewer, `/catalog/variant/${encodeURIComponent(shownId.textContent)}/visual.glb`, VARIANT_VIEW);
  }}, "3D view (built variants)");
  const update = () => {
    const variants = pairings[other.value].variants;
    const chosen = preset.value in variants ? preset.value : Object.keys(variants)[0];
    preset.replaceChildren(...Object.keys(variants).map((p) => el("option", {value: p}, p)));
    preset.value = chosen;
    pickedRobot = robot.value;
    const query = robot.value && robot.value !== state.robots.default ? `?robot=${encodeURIComponent(robot.value)}`
      : "";
    link.href = `/teleop/${encodeURIComponent(variants[chosen])}${query}`;
    shownId.textContent = variants[chosen];
    numbers.textContent = presetSummary(state.presets[chosen]);
  };
  const changed = () => { update(); if (!viewer.hidden) show3d.click(); };
  other.addEventListener("change", changed);
  preset.addEventListener("change", changed);
  robot.addEventListener("change", update);
  update();
  return el("div", {class: "pairing"}, el("label", {}, `${noun} `, other), el("label", {}, "preset ", preset),
            state.robots.robots.length ? el("label", {}, "robot ", robot) : null, numbers, link, show3d, shownId, viewer);
}
let pickedRobot = null; // the robot last picked, kept from one entry to the next

// ---- presets: the numbers behind each --------------------------------------------------------------------------
const UNITS = {slide: {damping: "N·s/m", frictionloss: "N", armature: "kg", spring: "N/m", length: "m"},
               hinge: {damping: "N·m·s/rad", frictionloss: "N·m", armature: "kg·m²", spring: "N·m/rad",
                       length: "rad"}};
// the units of the effects' fields (rik/schemas/joints.py), slide then hinge
const EFFECT_UNITS = {breakaway: ["N", "N·m"], stribeck_velocity: ["m/s", "rad/s"], zone: ["m", "rad"],
                      damping: ["N·s/m", "N·m·s/rad"], stiffness: ["N/m", "N·m/rad"], force: ["N", "N·m"],
                      decay: ["m", "rad"], sine: ["N", "N·m"], extra: ["N", "N·m"],
                      coefficient: ["N·s²/m²", "N·m·s²/rad²"], per_extension: ["N/m", "N·m/rad"]};

function jointNumbers(joint, kind) {
  if (!joint) return "–";
  const u = UNITS[kind];
  const parts = [`damping ${num(joint.damping)} ${u.damping}`, `friction ${num(joint.frictionloss)} ${u.frictionloss}`];
  if (joint.armature) parts.push(`armature ${num(joint.armature)} ${u.armature}`);
  if (joint.spring) {
    parts.push(`spring ${num(joint.spring.stiffness)} ${u.spring} (rest at ${num(joint.spring.reference)} ${u.length})`);
  }
  for (const effect of joint.effects || []) { // effects identified by rik sysid: their fields as the schema names them
    const unit = (k) => (EFFECT_UNITS[k] ? ` ${EFFECT_UNITS[k][kind === "slide" ? 0 : 1]}` : "");
    const fields = Object.entries(effect).filter(([k]) => k !== "kind").map(([k, v]) => `${k.replaceAll("_", " ")} `
      + (typeof v === "number" ? `${num(v)}${unit(k)}` : String(v)));
    parts.push(`${effect.kind.replaceAll("_", " ")} (${fields.join(", ")})`);
  }
  return parts.join(", ");
}

function presetSummary(p) {
  return p ? `${p.id}: slide ${jointNumbers(p.slide, "slide")}; hinge ${jointNumbers(p.hinge, "hinge")}` : "";
}

function presetTable() {
  const rows = Object.values(state.presets);
  return el("table", {id: "presets"},
    el("thead", {}, el("tr", {}, ["preset", "slide (drawers)", "hinge (doors, flaps)", "source"].map(
      (h) => el("th", {}, h)))),
    el("tbody", {}, rows.map((p) => el("tr", {"data-id": p.id},
      el("th", {}, p.id, el("br"), el("span", {class: "note"}, p.name), p.in_default_set
        ? el("span", {class: "badge"}, "default") : null),
      el("td", {}, jointNumbers(p.slide, "slide")), el("td", {}, jointNumbers(p.hinge, "hinge")),
      el("td", {class: "note"}, `${p.source.kind}: ${p.source.reference || ""}`)))));
}

// ---- 3D view ----------------------------------------------------------------------------------------------
// three.js is loaded only when a panel shows a model (a module import from this classic script).
const HANDLE_VIEW = {up: [0, 1, 0], view: [0.6, 0.5, 1]}; // mount frame: +z out of the front, y up
const VARIANT_VIEW = {up: [0, 0, 1], view: [-0.6, 1.2, 0.7]}; // MuJoCo's frame: z up, the fronts face +y
function view3d(element, url, options) {
  element.dataset.ready = "0";
  import("/static/viewer3d.js").then((m) => m.mount(element, url, options)).catch((err) => {
    element.textContent = `rik: the 3D view failed: ${err.message}`;
    element.dataset.ready = "error";
  });
}

// ---- detail panel -----------------------------------------------------------------------------------------
function showDetail(...children) {
  $("#detail-body").replaceChildren(...children);
  $("#detail").hidden = false;
  $("#detail").scrollTop = 0;
  document.body.classList.add("with-detail");
}

function closeDetail(push) {
  $("#detail").hidden = true;
  document.body.classList.remove("with-detail");
  for (const c of document.querySelectorAll(".card.selected")) c.classList.remove("selected");
  if (push) history.pushState({}, "", "/catalog" + location.search + (activeTab() === "handles" ? "" : `#${activeTab()}`));
}

function select(card) {
  for (const c of document.querySelectorAll(".card.selected")) c.classList.remove("selected");
  if (card) card.classList.add("selected");
}

async function openHandle(id, push) {
  const h = await getJSON(`/api/catalog/handles/${path(id)}`);
  if (push) history.pushState({}, "", `/catalog/handle/${path(id)}${location.search}`);
  showTab("handles");
  select(document.querySelector(`#handle-grid .card[data-id="${CSS.escape(id)}"]`));
  const dims = Object.entries(h.display).filter(([k]) => !["id", "type"].includes(k));
  const mesh = h.mesh ? table([
    ["vertices", fmt(h.mesh.vertices)], ["faces", fmt(h.mesh.faces)],
    ["mean edge length, mm", fmt(h.mesh.mean_edge_mm)], ["mean face area, mm²", fmt(h.mesh.mean_face_area_mm2, 3)],
    ["watertight", fmt(h.mesh.watertight)], ["collision hulls (CoACD)", fmt(h.mesh.hulls)],
    ["collision vertices", fmt(h.mesh.collision_vertices)]]) : el("p", {class: "note"}, "No mesh statistics "
    + "(run rik assets stats).");
  const f = h.fidelity;
  const rows = [["mean", "mean"], ["95th percentile", "p95"], ["max", "max"]];
  const fidelity = f ? [
    table([...rows.map(([label, k]) => [`E_Q→P ${label}`, fmt(f.coacd[`eqp_${k}_mm`]), fmt(f.hull[`eqp_${k}_mm`])]),
           ...rows.map(([label, k]) => [`E_P→Q ${label}`, fmt(f.coacd[`epq_${k}_mm`]), fmt(f.hull[`epq_${k}_mm`])])],
          ["distance, mm", `CoACD (${f.hulls} hulls)`, "single convex hull"]),
    el("p", {class: "note"}, `The single hull strays ${fmt(f.hull_over_coacd, 1)}× as far from the visual surface `
       + "as rik's CoACD collision (E_Q→P: collision to visual; E_P→Q: visual to collision)."),
  ] : [el("p", {class: "note"}, "No fidelity numbers (run rik assets fidelity).")];
  showDetail(
    el("h2", {id: "detail-title"}, h.id),
    el("p", {}, `${h.design_name} · ${TYPE_LABEL[h.type]} · `, el("span", {class: "badge"}, `split ${h.split}`),
       h.origin === "overlay" ? el("span", {class: "badge"}, "user catalog") : null),
    el("div", {class: "pictures"},
       el("img", {class: "thumb", src: `/catalog/img/${path(h.id)}/thumbnail.png`, alt: `thumbnail of ${h.id}`}),
       el("div", {id: "viewer-handle", class: "viewer3d", title: "drag to turn, wheel to zoom"})),
    el("h3", {}, "Dimensions"), el("div", {id: "dimensions"}, table(dims)),
    el("h3", {}, "Build and teleoperate"),
    el("p", {class: "note"}, `Fits ${h.pairings.length} of ${state.bases.length} base units.`),
    picker(h.pairings, "base unit", false),
    el("h3", {}, "Collision fidelity"),
    el("img", {id: "fidelity-img", class: "heatmap", src: `/catalog/img/${path(h.id)}/fidelity.png`,
               alt: `collision-error heatmaps of ${h.id}`}),
    el("div", {id: "fidelity"}, fidelity),
    el("h3", {}, "Mesh statistics"), el("div", {id: "mesh-stats"}, mesh));
  view3d($("#viewer-handle"), `/catalog/model/${path(h.id)}/visual.glb`, HANDLE_VIEW);
}

async function openBase(id, push) {
  const b = await getJSON(`/api/catalog/bases/${path(id)}`);
  if (push) history.pushState({}, "", `/catalog/base/${path(id)}${location.search}`);
  showTab("bases");
  select(document.querySelector(`#base-grid .card[data-id="${CSS.escape(id)}"]`));
  const dims = Object.entries(b.display).filter(([k]) => k !== "id");
  showDetail(
    el("h2", {id: "detail-title"}, b.id),
    el("p", {}, b.description),
    el("img", {class: "front", src: `/catalog/img/${path(b.id)}/front.svg`, alt: `front view of ${b.id}`}),
    el("h3", {}, "Dimensions"), el("div", {id: "dimensions"}, table(dims)),
    el("h3", {}, "Fronts"),
    table(b.fronts_mm.map((f) => [f.id, f.kind, f.joint, `${fmt(f.size[0], 0)} × ${fmt(f.size[1], 0)}`,
                                  `${fmt(f.mount[0], 0)} × ${fmt(f.mount[1], 0)}`]),
          ["front", "kind", "joint", "size mm", "mount area mm"]),
    el("h3", {}, "Build and teleoperate"),
    el("p", {class: "note"}, `${b.pairings.length} of ${state.handles.length} handles fit; default preset `
       + `${b.default_preset}.`),
    picker(b.pairings, "handle", true));
}

// ---- tabs, routes, start ----------------------------------------------------------------------------------
function activeTab() { return TABS.find((tab) => !$(`#${tab}-tab`).hidden) || "handles"; }

function showTab(tab) {
  for (const t of TABS) $(`#${t}-tab`).hidden = tab !== t;
  for (const b of document.querySelectorAll("#tabs button")) b.classList.toggle("active", b.dataset.tab === tab);
}

async function route() {
  const match = location.pathname.match(/^\/catalog\/(handle|base)\/(.+)$/);
  restoreFilters();
  applyFilters();
  try {
    if (!match) {
      $("#detail").hidden = true;
      document.body.classList.remove("with-detail");
      showTab(TABS.includes(location.hash.slice(1)) ? location.hash.slice(1) : "handles");
    } else {
      const id = match[2].split("/").map(decodeURIComponent).join("/");
      await (match[1] === "handle" ? openHandle(id, false) : openBase(id, false));
    }
  } catch (err) {
    fail(err);
  }
}

function fail(err) {
  $("#error").textContent = `rik: ${err.message}`;
  $("#error").hidden = false;
}

async function start() {
  const [h, b, r, p] = await Promise.all([getJSON("/api/catalog/handles"), getJSON("/api/catalog/bases"),
                                          getJSON("/teleop/robots.json"), getJSON("/api/catalog/presets")]);
  state.robots = r;
  state.presets = Object.fromEntries(p.presets.map((preset) => [preset.id, preset]));
  $("#n-presets").textContent = `(${p.count})`;
  $("#preset-table").replaceChildren(presetTable());
  state.handles = h.handles;
  state.bases = b.bases;
  $("#n-handles").textContent = `(${h.count})`;
  $("#n-bases").textContent = `(${b.count})`;
  $("#summary").textContent = `${h.count} handles, ${b.count} base units; ${h.pairings.fit} of `
    + `${h.pairings.total} pairings fit`;
  $("#handle-grid").replaceChildren(...state.handles.map(handleCard));
  $("#base-grid").replaceChildren(...state.bases.map((base) => el("a", {
    class: "card base", href: `/catalog/base/${path(base.id)}`, "data-id": base.id,
    onclick: (e) => { e.preventDefault(); openBase(base.id, true).catch(fail); }},
    el("img", {src: `/catalog/img/${path(base.id)}/front.svg`, alt: `front view of ${base.id}`}),
    el("div", {class: "title"}, base.id),
    el("div", {class: "meta"}, base.name),
    el("div", {class: "meta"}, `${base.display.fronts} · ${base.joint_types.join(", ")}`))));
  $("#bases-count").textContent = `${b.count} base units; each pairs with the handles that fit every one of its `
    + "fronts.";
  setupFilters(h.finishes);
  for (const button of document.querySelectorAll("#tabs button")) {
    button.addEventListener("click", () => { showTab(button.dataset.tab); closeDetail(true); });
  }
  $("#detail-close").addEventListener("click", () => closeDetail(true));
  document.addEventListener("keydown", (e) => { if (e.key === "Escape" && !$("#detail").hidden) closeDetail(true); });
  window.addEventListener("popstate", route);
  await route();
  document.body.dataset.ready = "1";
}

start().catch(fail);
