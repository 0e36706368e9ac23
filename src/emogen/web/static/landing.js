// Consent page: take the participant id from the URL, start (or resume) the session.
import { api } from "./api.js";
import { statusText } from "./connection.js";

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

/** @type {import("./connection.js").Link} */
let link = { kind: "online" };
/** @type {ReturnType<typeof setInterval> | undefined} */
let ticker;

/** While the server asks this address to wait (a room starting at once): a countdown. */
function paintLink() {
  message.textContent = statusText(link, Date.now());
  body.dataset.link = link.kind;
}

/** @param {import("./connection.js").Link} next */
function onLink(next) {
  link = next;
  clearInterval(ticker);
  if (link.kind !== "online") ticker = setInterval(paintLink, 250);
  paintLink();
}

agree.addEventListener("click", async () => {
  agree.disabled = true;
  message.textContent = "";
  try {
    const created = await api("/api/sessions", {
      method: "POST",
      body: { participant_id: participant || null, resume_token: remembered() },
      waitIfCrowded: true,
      onLink,
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
