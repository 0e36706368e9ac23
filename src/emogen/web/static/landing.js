// Consent page: take the participant id from the URL, start (or resume) the session.
import { api } from "./api.js";

const body = document.body;
const study = body.dataset.study;
const params = new URLSearchParams(location.search);
const participant = params.get(body.dataset.param) || params.get("participant") || "";
const storageKey = `emogen:${study}:${participant || "anonymous"}`;
const message = document.getElementById("message");
const agree = document.getElementById("agree");

if (participant) {
  document.getElementById("participant-id").textContent = participant;
  document.getElementById("participant-line").hidden = false;
}

function remembered() {
  try {
    return localStorage.getItem(storageKey);
  } catch {
    return null;
  }
}

agree.addEventListener("click", async () => {
  agree.disabled = true;
  message.textContent = "";
  try {
    const created = await api("/api/sessions", {
      method: "POST",
      body: { participant_id: participant || null, resume_token: remembered() },
    });
    try {
      localStorage.setItem(storageKey, created.token);
    } catch {
      /* private mode: the session link still works */
    }
    location.replace(created.url);
  } catch (err) {
    message.textContent = err.message;
    agree.disabled = false;
  }
});

// Already consented in this browser: go straight back to the session.
const token = remembered();
if (token) {
  fetch(`/api/s/${token}/state`, { cache: "no-store" }).then((r) => {
    if (r.ok) location.replace(`/s/${token}`);
  });
}
