// The study page's entry into the face viewer (src/emogen/web/viewer): bundled by
// build.mjs into static/build/study-viewer.js, imported by static/viewer-adapter.js.
export { FaceGrid } from "./viewer/faces.js";
export { ovalLayer } from "./viewer/look.js";
