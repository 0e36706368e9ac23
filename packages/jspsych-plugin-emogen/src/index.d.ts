// TypeScript declarations of the plugin (copied to dist/index.d.ts by build.mjs; the bundle
// itself is built from src/index.js). tests/web/test_jspsych_package.py type-checks a page's
// timeline against them with tsc.
import type { JsPsych, JsPsychPlugin, ParameterType, TrialType } from "jspsych";

declare const info: {
  readonly name: "emogen";
  readonly version: string;
  readonly parameters: {
    /** The study server's address, ``https://host[:port]``. */
    readonly server: { readonly type: ParameterType.STRING; readonly default: undefined };
    /** The task the timeline expects; the trial runs the study's current trial. */
    readonly task: { readonly type: ParameterType.SELECT; readonly options: readonly string[]; readonly default: string };
    readonly participant_id: { readonly type: ParameterType.STRING; readonly default: null };
    readonly participant_param: { readonly type: ParameterType.STRING; readonly default: null };
    readonly render: { readonly type: ParameterType.SELECT; readonly options: readonly ["auto", "png"]; readonly default: "auto" };
    readonly timeout_ms: { readonly type: ParameterType.INT; readonly default: number };
    readonly patience_ms: { readonly type: ParameterType.INT; readonly default: number };
    readonly load_timeout_ms: { readonly type: ParameterType.INT; readonly default: number };
    readonly failure_wait_ms: { readonly type: ParameterType.INT; readonly default: null };
  };
  /** Every data field, ``emogen_<name>`` (and jsPsych's ``rt``): docs/jspsych.md. */
  readonly data: Record<string, { type: ParameterType; array?: boolean; nested?: Record<string, unknown> }>;
  readonly citations: { readonly apa: string; readonly bibtex: string };
};

type Info = typeof info;

/** jsPsych 8 plugin: one trial of an EmoGen study (evolve or categorise), run by ``emogen serve``. */
declare class EmogenPlugin implements JsPsychPlugin<Info> {
  static info: Info;
  constructor(jsPsych: JsPsych);
  trial(display_element: HTMLElement, trial: TrialType<Info>, on_load: () => void): Promise<Record<string, unknown>>;
  simulate(
    trial: TrialType<Info>,
    simulation_mode: "data-only" | "visual",
    simulation_options: Record<string, unknown>,
    on_load: () => void,
  ): Promise<Record<string, unknown>>;
}

export default EmogenPlugin;
export declare const VERSION: string;
