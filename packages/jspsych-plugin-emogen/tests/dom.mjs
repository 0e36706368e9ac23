// A browser page for the node tests (jsdom), set up before jsPsych is imported: the globals
// jsPsych and the study page's modules use, a page URL with a Prolific id, and images that
// "load" (jsdom fetches none) so the face display's PNG fallback finishes drawing.
import { JSDOM } from "jsdom";

const dom = new JSDOM("<!doctype html><html><head></head><body></body></html>", {
  url: "https://experiments.example.org/study/index.html?PROLIFIC_PID=node-participant",
  pretendToBeVisual: true,
});
const { window } = dom;
for (const name of [
  "window", "document", "location", "navigator", "sessionStorage", "localStorage", "HTMLElement",
  "HTMLInputElement", "HTMLButtonElement", "HTMLTextAreaElement", "HTMLImageElement", "Element",
  "Node", "Event", "KeyboardEvent", "MouseEvent", "requestAnimationFrame", "cancelAnimationFrame",
  "getComputedStyle", "URLSearchParams", "AbortController",
]) {
  Object.defineProperty(globalThis, name, { value: window[name], configurable: true, writable: true });
}
Object.defineProperty(window.HTMLImageElement.prototype, "src", {
  set(value) {
    this.setAttribute("src", value);
    setTimeout(() => this.onload && this.onload(), 0);
  },
  get() {
    return this.getAttribute("src");
  },
});
window.HTMLCanvasElement.prototype.getContext = () => null; // no WebGL: the server's images
export { window };
