// Researcher dashboard: progress of the study's sessions (needs the researcher token).
import { api } from "./api.js";

const $ = (id) => document.getElementById(id);
let token = sessionStorage.getItem("emogen-researcher") || "";

function headers() {
  return { Authorization: `Bearer ${token}` };
}

// Generations numbered as the participant's page shows them: "Generation 3 of 11", "Rating".
function shownGeneration(s) {
  if (s.stage !== "trial") return "";
  if (s.generation_shown === null || s.generation_shown === undefined) return "rating";
  return `${s.generation_shown} of ${s.generations_shown}`;
}

// The participant's personal session link, fetched only when asked for (never in the table);
// links shown stay shown when the table refreshes.
const shownLinks = new Map();

function linkField(td, participant, url) {
  const field = document.createElement("input");
  field.type = "text";
  field.readOnly = true;
  field.value = url;
  field.setAttribute("aria-label", `session link of ${participant}`);
  td.replaceChildren(field);
  return field;
}

function linkCell(participant) {
  const td = document.createElement("td");
  if (shownLinks.has(participant)) {
    linkField(td, participant, shownLinks.get(participant));
    return td;
  }
  const button = document.createElement("button");
  button.type = "button";
  button.className = "link";
  button.textContent = "show link";
  button.addEventListener("click", async () => {
    try {
      const link = await api(
        `/api/researcher/participants/${encodeURIComponent(participant)}/link`,
        { headers: headers(), retries: 0 },
      );
      shownLinks.set(participant, link.url);
      linkField(td, participant, link.url).select();
    } catch (err) {
      $("message").textContent = err.message;
    }
  });
  td.appendChild(button);
  return td;
}

/** A table row of these cells (numbers right-aligned). */
function row(cells) {
  const tr = document.createElement("tr");
  for (const v of cells) {
    const td = document.createElement("td");
    td.textContent = v === null || v === undefined ? "" : String(v);
    if (typeof v === "number") td.className = "n";
    tr.appendChild(td);
  }
  return tr;
}

// "2025-03-04 14:10" (UTC, as stored): the time without seconds and zone.
const shortTime = (iso) => (iso ? iso.slice(0, 16).replace("T", " ") : "");

const minutes = (seconds) => (seconds === null || seconds === undefined ? "" : (seconds / 60).toFixed(1));

function showWarnings(warnings) {
  const list = $("warnings");
  list.replaceChildren(...warnings.map((w) => {
    const li = document.createElement("li");
    li.textContent = w;
    return li;
  }));
  list.hidden = warnings.length === 0;
}

function showDurations(status) {
  const d = status.durations;
  const [low, high] = status.estimate.minutes;
  let text = `Estimated session length: about ${low}–${high} min (${status.estimate.basis}; restarts not counted).`;
  if (d.completed > 0) {
    const quartiles = d.quartiles_min ? ` (quartiles ${d.quartiles_min[0]}–${d.quartiles_min[1]})` : "";
    text = `Completed sessions took ${d.median_min} min (median of ${d.completed})${quartiles}. ${text}`;
  }
  $("durations").textContent = text;
  $("durations").hidden = false;
}

function showConditions(conditions) {
  $("conditions").querySelector("tbody").replaceChildren(...conditions.map((c) =>
    row([c.block, c.task, c.emotion, c.identity, c.assigned, c.started, c.done])));
}

function showRows(cb) {
  const table = $("rows");
  table.hidden = !cb.rows;
  if (!cb.rows) return;
  const how = cb.counterbalance === "arrival" ? "exact, in arrival order" : "from a hash of the participant id";
  $("rows-caption").textContent = `Counterbalancing: sessions per Latin-square row (${how})`;
  table.querySelector("tbody").replaceChildren(...cb.rows.map((r) => row([r.row, r.sessions, r.done])));
}

function showBlockOrders(orders) {
  const table = $("block-orders");
  table.hidden = !orders || orders.length === 0;
  if (table.hidden) return;
  table.querySelector("tbody").replaceChildren(...orders.map((o) => row([o.order.replaceAll(">", " → "), o.sessions, o.done])));
}

function sessionRow(s) {
  const tr = row([s.session_id, s.session_number, s.participant_id, s.stage, `${s.trial} of ${s.trials}`,
    shownGeneration(s), s.attempt ?? "", s.order_row ?? "", minutes(s.duration_s), shortTime(s.created_at), shortTime(s.updated_at)]);
  tr.appendChild(linkCell(s.participant_id));
  return tr;
}

async function refresh() {
  try {
    const status = await api("/api/researcher/status", { headers: headers(), retries: 0 });
    $("message").textContent = "";
    const mine = status.studies.find((s) => s.study_id === status.study_id);
    $("summary").textContent = mine
      ? `${mine.sessions} sessions (${Object.entries(mine.by_stage)
          .map(([k, v]) => `${v} ${k}`)
          .join(", ")}); ${mine.trials_done} trials done; steps: ${
          Object.entries(mine.steps)
            .map(([k, v]) => `${v} ${k}`)
            .join(", ") || "none"
        }.`
      : "No sessions yet.";
    showWarnings(status.warnings);
    showDurations(status);
    showConditions(status.conditions);
    showRows(status.counterbalancing);
    showBlockOrders(status.block_orders);
    $("sessions").querySelector("tbody").replaceChildren(...status.sessions.map(sessionRow));
    for (const id of ["details", "sessions", "downloads"]) $(id).hidden = false;
  } catch (err) {
    $("message").textContent = err.message;
  }
}

$("token-form").addEventListener("submit", (event) => {
  event.preventDefault();
  token = $("token").value;
  sessionStorage.setItem("emogen-researcher", token);
  refresh();
});

$("downloads").addEventListener("click", async (event) => {
  const { table, format } = event.target.dataset || {};
  if (!table || !format) return;
  const name = `${table}.${format}`;
  $("message").textContent = `Preparing ${name} …`;
  const response = await fetch(`/api/researcher/export/${name}`, { headers: headers() });
  if (!response.ok) {
    const body = await response.json().catch(() => ({}));
    $("message").textContent = `The export of ${name} failed: ${body.detail || response.statusText}`;
    return;
  }
  const url = URL.createObjectURL(await response.blob());
  const a = document.createElement("a");
  a.href = url;
  a.download = name;
  a.click();
  URL.revokeObjectURL(url);
  $("message").textContent = "";
});

if (token) refresh();
setInterval(() => token && refresh(), 15000);
