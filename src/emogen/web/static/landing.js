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

/** A random key made once in this browser before the first try to start the session, sent with
 * every try: when an answer is lost (a crash after the commit, a proxy timeout, a mobile drop)
 * the retry gets the same session instead of "already has a session". */
let madeKey = "";
function createKey() {
  const name = `${storageKey}:create-key`;
  try {
    madeKey = madeKey || localStorage.getItem(name) || "";
  } catch {
    /* private mode: the key lives as long as the page */
  }
  if (!madeKey) {
    const bytes = crypto.getRandomValues(new Uint8Array(18));
    madeKey = btoa(String.fromCharCode(...bytes)).replace(/\+/g, "-").replace(/\//g, "_");
    try {
      localStorage.setItem(name, madeKey);
    } catch {
      /* private mode */
    }
  }
  return madeKey;
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
      body: {
        participant_id: participant || null,
        resume_token: remembered(),
        create_key: createKey(),
      },
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
