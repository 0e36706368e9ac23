// eslint (flat config): the browser JS (participant, researcher and viewer pages), the build
// script and the JS unit tests. `npx eslint .` (run by `make lint`).
import js from "@eslint/js";
import globals from "globals";

export default [
  { ignores: ["node_modules/**", "src/emogen/web/static/build/**", "**/*.d.ts", ".venv/**", "packages/*/dist/**"] },
  js.configs.recommended,
  {
    files: ["src/emogen/web/**/*.js"],
    languageOptions: { ecmaVersion: 2022, sourceType: "module", globals: globals.browser },
  },
  {
    files: ["**/*.mjs"],
    languageOptions: { ecmaVersion: 2022, sourceType: "module", globals: globals.node },
  },
  {
    // the jsPsych plugin runs in the page; its node tests in a jsdom page
    files: ["packages/*/src/**/*.js", "packages/*/tests/**/*.mjs"],
    languageOptions: { ecmaVersion: 2022, sourceType: "module", globals: { ...globals.browser, ...globals.node } },
  },
  {
    rules: {
      "no-unused-vars": ["error", { argsIgnorePattern: "^_", caughtErrors: "none" }],
      eqeqeq: "error",
      "prefer-const": "error",
    },
  },
];
