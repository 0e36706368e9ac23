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

async function refresh() {
  try {
    const status = await api("/api/researcher/status", { headers: headers(), retries: 0 });
    $("message").textContent = "";
    const mine = status.studies.find((s) => s.study_id === status.study_id);
    $("summary").textContent = mine
      ? `${mine.sessions} sessions (${Object.entries(mine.by_stage)
          .map(([k, v]) => `${v} ${k}`)
          .join(", ")}); ${mine.trials_done} trials done; ${mine.selections} selections.`
      : "No sessions yet.";
    const body = $("sessions").querySelector("tbody");
    body.replaceChildren();
    for (const s of status.sessions) {
      const tr = document.createElement("tr");
      for (const v of [s.session_id, s.participant_id, s.stage, `${s.trial} of ${s.trials}`,
        shownGeneration(s), s.attempt ?? "", s.created_at, s.updated_at]) {
        const td = document.createElement("td");
        td.textContent = String(v);
        tr.appendChild(td);
      }
      tr.appendChild(linkCell(s.participant_id));
      body.appendChild(tr);
    }
    $("sessions").hidden = false;
    $("downloads").hidden = false;
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
  const table = event.target.dataset && event.target.dataset.table;
  if (!table) return;
  const response = await fetch(`/api/researcher/export/${table}.csv`, { headers: headers() });
  if (!response.ok) {
    $("message").textContent = `export failed (${response.status})`;
    return;
  }
  const url = URL.createObjectURL(await response.blob());
  const a = document.createElement("a");
  a.href = url;
  a.download = `${table}.csv`;
  a.click();
  URL.revokeObjectURL(url);
});

if (token) refresh();
setInterval(() => token && refresh(), 15000);
