// Builds the plugin (`npm run build` here, or `node packages/jspsych-plugin-emogen/build.mjs`)
// with the project's esbuild, from the study page's own modules (src/emogen/web/static) and
// face viewer (src/emogen/web/viewer, three.js from npm) — one implementation, two pages:
//   dist/index.js               ES module (import EmogenPlugin from "jspsych-plugin-emogen")
//   dist/index.browser.min.js   <script> build: the global jsPsychEmogen (jsPsych's jsPsychModule)
//   dist/emogen.css             the study page's styles, scoped to the trial (.emogen-trial)
//   dist/index.d.ts             TypeScript declarations (src/index.d.ts)
import { copyFile, mkdir, readFile, writeFile } from "node:fs/promises";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";
import * as esbuild from "esbuild";

const here = dirname(fileURLToPath(import.meta.url));
const web = join(here, "..", "..", "src", "emogen", "web");
const out = join(here, "dist");

// static/viewer-adapter.js imports the viewer's built bundle (build/study-viewer.js); the
// plugin bundles the viewer from its source instead (the same module, built once here).
// The study page's own way to its viewer (faces.js: import("/static/viewer-adapter.js"), an
// address on the study server) is the same module the plugin bundles: resolved to it, so that
// no import of a server address is left for a lab's bundler to trip on.
const viewerFromSource = {
  name: "viewer-from-source",
  setup(build) {
    build.onResolve({ filter: /\/build\/study-viewer\.js$/ }, () => ({ path: join(web, "viewer_entry.js") }));
    build.onResolve({ filter: /^\/static\/viewer-adapter\.js$/ }, () => ({ path: join(web, "static", "viewer-adapter.js") }));
  },
};
// The <script> build takes jsPsych from the page (jsPsych's own script: window.jsPsychModule).
const jspsychGlobal = {
  name: "jspsych-global",
  setup(build) {
    build.onResolve({ filter: /^jspsych$/ }, () => ({ path: "jspsych", namespace: "jspsych-global" }));
    build.onLoad({ filter: /.*/, namespace: "jspsych-global" }, () => ({
      contents: "module.exports = window.jsPsychModule;",
      loader: "js",
    }));
  },
};
const common = {
  entryPoints: [join(here, "src", "index.js")],
  bundle: true,
  target: ["es2020"],
  loader: { ".glsl": "text" },
  legalComments: "eof",
  logLevel: "warning",
};

/** study.css under .emogen-trial: its :root and body rules become the trial's own. The trial
 * has a fixed width (jsPsych sizes its content to fit): it never jumps wider when a click
 * changes what it shows, and a categorise face has its labels beside it on a desktop. */
async function scopedCss() {
  const css = await readFile(join(web, "static", "study.css"), "utf8");
  const nested = css
    .replace(/:root\b/g, "&")
    .replace(/^body(?=[\s[{])/gm, "&")
    .replace(/^(\s*)body\[/gm, "$1&[");
  const own = `
  & { min-height: 0; text-align: left; width: min(1280px, 96vw); }
  & .bar:has(#gen-progress:empty) { grid-template-columns: minmax(0, 1fr); }
  & .bar:has(#gen-progress:empty) .progress { display: none; }
  & .emogen-main { position: relative; }
  & .text-page h2 { margin-top: 1rem; }`;
  const { code } = await esbuild.transform(`.emogen-trial {\n${nested}\n${own}\n}`, {
    loader: "css",
    target: ["chrome90", "firefox88", "safari14"],
    minify: true,
  });
  return code;
}

await mkdir(out, { recursive: true });
await Promise.all([
  esbuild.build({ ...common, format: "esm", minify: true, outfile: join(out, "index.js"), external: ["jspsych"], plugins: [viewerFromSource] }),
  esbuild.build({
    ...common,
    format: "iife",
    minify: true,
    globalName: "jsPsychEmogen",
    footer: { js: "jsPsychEmogen = jsPsychEmogen.default;" },
    outfile: join(out, "index.browser.min.js"),
    plugins: [viewerFromSource, jspsychGlobal],
  }),
  scopedCss().then((css) => writeFile(join(out, "emogen.css"), css)),
  copyFile(join(here, "src", "index.d.ts"), join(out, "index.d.ts")),
]);
await writeFile(join(out, ".built"), "");
console.log(`jspsych-plugin-emogen built in ${out}: index.js, index.browser.min.js, emogen.css, index.d.ts`);
