// The page of recorded episodes and built datasets of rik serve: /api/episodes drawn as two tables. Every value
// comes from files in the app's folders (untrusted): it is put in the page as text (textContent), never as HTML.
// A row whose metadata is damaged holds the server's one line saying so. Plain JavaScript, no build step.
"use strict";

const $ = (selector) => document.querySelector(selector);

function cell(text, cls = "") {
  const td = document.createElement("td");
  if (cls) td.className = cls;
  td.textContent = text === null || text === undefined ? "–" : String(text);
  return td;
}

function pct(x) { return typeof x === "number" ? `${(100 * x).toFixed(1)} %` : "–"; }

function damaged(tr, name, error, span) { // a row whose metadata could not be read: its name and the one line why
  tr.className = "damaged";
  const why = cell(error);
  why.colSpan = span;
  tr.append(cell(name), why);
  return tr;
}

function episodeRow(e) {
  const tr = document.createElement("tr");
  tr.dataset.id = e.id;
  if (e.error) return damaged(tr, e.id, e.error, 9);
  tr.append(cell(e.id), cell(e.variant), cell(e.robot), cell(`${e.operator} (${e.operator_kind})`),
            cell(`${e.outcome} (${e.outcome_name})`, `outcome-${e.outcome}`), cell(pct(e.final_opening), "num"),
            cell(pct(e.max_opening), "num"), cell(e.steps, "num"), cell(e.seconds.toFixed(2), "num"));
  const replay = document.createElement("td");
  if (e.replay) {
    const a = document.createElement("a");
    a.href = e.replay; // built by the server from the validated meta (ids are path components, quoted)
    a.className = "replay";
    a.textContent = "replay";
    a.title = "open this variant's station with this robot and replay the episode there";
    replay.append(a);
  } else {
    replay.textContent = "its folder is not named by its id";
  }
  tr.append(replay);
  return tr;
}

function datasetRow(d) {
  const tr = document.createElement("tr");
  tr.dataset.name = d.name;
  if (d.error) return damaged(tr, d.name, d.error, 7);
  const outcomes = Object.entries(d.outcomes || {}).map(([k, n]) => `${k} ${n}`).join(", ");
  tr.append(cell(d.name), cell(d.repo_id), cell(d.robot), cell(d.episodes, "num"), cell(d.frames, "num"),
            cell(d.variants, "num"), cell(outcomes), cell((d.streams || []).join(", ")));
  return tr;
}

function note(shown, total, noun, folder) {
  if (!total) return `No ${noun} in ${folder}.`;
  return `${shown === total ? total : `${shown} newest of ${total}`} ${noun} in ${folder}.`;
}

async function start() {
  const response = await fetch("/api/episodes");
  const body = await response.json();
  if (!response.ok) throw new Error(body.detail || response.statusText);
  $("#episodes tbody").replaceChildren(...body.episodes.map(episodeRow));
  $("#datasets tbody").replaceChildren(...body.datasets.map(datasetRow));
  $("#episodes-note").textContent = note(body.episodes.length, body.episodes_total, "episodes", body.episodes_folder)
    + " Replay opens the episode's station, which plays it back from its recorded states.";
  $("#datasets-note").textContent = note(body.datasets.length, body.datasets_total, "datasets", body.datasets_folder);
  const damaged = body.episodes.filter((e) => e.error).length;
  $("#summary").textContent = `${body.episodes.length} episodes (${damaged} unreadable), ${body.datasets.length} `
    + "datasets";
  document.body.dataset.ready = "1";
}

start().catch((err) => {
  $("#error").textContent = `rik: ${err.message}`;
  $("#error").hidden = false;
});
