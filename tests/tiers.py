"""Which tier each test runs in, and on which databases: the lists `tests/conftest.py` applies.

`make check` (the fast tier) runs every test not marked ``slow``, ``browser`` or ``postgres``;
`make test` runs them all. A test is marked in its own module where it is slow by nature
(``pytest.mark.slow``/``browser``); the lists below mark the rest from here, each with why:

- ``SLOW``: tests that take seconds each, measured on the 2-core machine shared with other
  jobs (load 6-7): over 2.5 s in one process, or over 3 s in the fast tier run on two xdist
  workers (issue #38: `make check` in about 3 minutes). They still run in `make test`.
- ``BOTH_DATABASES``: tests of what SQLite and PostgreSQL do differently (transactions, locks,
  idempotency, migrations, column types, faults). They run on both; the PostgreSQL case is
  marked ``postgres``. Every other test asking for ``db_url`` runs on SQLite only, unless it
  pins its backends itself (``@pytest.mark.parametrize("db_url", [...], indirect=True)``).

An entry is ``path::test`` (every parameter of it) or ``path::test[id]`` (one), or a module's
path (each of its tests). An entry that names no collected test of a collected module is an
error, so a renamed test cannot drop out of its tier unnoticed.
"""

from __future__ import annotations

_SECONDS = "takes seconds (call time in s, one process, load ~7)"
_PARALLEL = "takes seconds in the fast tier (s, two xdist workers, load ~6)"

#: Moved from the fast tier to ``slow`` (issue #38: `make check` in ≤ 3 minutes).
SLOW: dict[str, str] = {
    "tests/ga/test_motion.py::test_interpenetration_between_keyframes_stays_within_the_measured_bound": f"{_SECONDS}: 39",
    "tests/analysis/test_analyse_people.py::test_one_repetition_says_why_there_is_no_reliability": f"{_SECONDS}: 4.2",
    "tests/analysis/test_analyse_people.py::test_reliability_and_groups_with_the_participant_as_unit": f"{_SECONDS}: 6.8 (+24 s fixture)",
    "tests/analysis/test_analyse_simulation.py::test_analyse_simulations_end_to_end": f"{_SECONDS}: 3.2",
    "tests/analysis/test_analyse_study.py::test_analyse_a_study_export": f"{_SECONDS}: 7.3",
    "tests/analysis/test_categorisation_clogit.py::test_a_planted_own_face_effect_is_found": f"{_SECONDS}: 15.2",
    "tests/analysis/test_categorisation_clogit.py::test_labels_that_ignore_the_faces_give_results_or_reasons_never_nan": f"{_SECONDS}: 11.8",
    "tests/analysis/test_categorisation_models.py::test_the_contrast_holds_alpha_when_prototypes_are_shuffled": f"{_SECONDS}: 3.1",
    "tests/analysis/test_conditions.py::test_identity_tests_hold_alpha_on_null_and_find_a_planted_effect": f"{_SECONDS}: 3.7",
    "tests/analysis/test_fields.py::test_one_population_mostly_reads_as_no_structure": f"{_SECONDS}: 9.0",
    "tests/analysis/test_fields.py::test_contact_sheets_show_a_seeded_sample_of_a_large_study": f"{_SECONDS}: 8.8",
    "tests/analysis/test_fields_accuracy.py::test_a_planted_relation_is_found": f"{_SECONDS}: 8.6",
    "tests/analysis/test_fields_accuracy.py::test_labels_that_ignore_the_faces_hold_alpha": f"{_SECONDS}: 27.9",
    "tests/analysis/test_figures.py::test_bar_and_curve_figures_hold_for_2_to_12_groups[12]": f"{_SECONDS}: 3.6",
    "tests/analysis/test_genes.py::test_family_wise_error_on_null_data": f"{_SECONDS}: 5.2",
    "tests/analysis/test_identity.py::test_false_positive_rate_without_identity_effect": f"{_SECONDS}: 5.8",
    "tests/analysis/test_noise_calibration.py::test_a_pool_few_times_the_group_stays_calibrated": f"{_SECONDS}: 3.1",
    "tests/analysis/test_noise_calibration.py::test_the_latent_target_test_as_analyse_runs_it_is_calibrated": f"{_SECONDS}: 11.1",
    "tests/analysis/test_noise_empirical.py::test_one_shared_prototype_is_flagged_at_most_at_alpha": f"{_SECONDS}: 3.5",
    "tests/analysis/test_power.py::test_identical_prototypes_on_the_ga_reject_at_alpha": f"{_SECONDS}: 18.1",
    "tests/appearance/test_framing_cache.py::test_a_lit_cheek_renders_at_its_monk_swatch[2]": f"{_SECONDS}: 3.9",
    "tests/appearance/test_framing_cache.py::test_a_lit_cheek_renders_at_its_monk_swatch[5]": f"{_SECONDS}: 3.4",
    "tests/appearance/test_framing_cache.py::test_a_lit_cheek_renders_at_its_monk_swatch[8]": f"{_SECONDS}: 3.0",
    "tests/appearance/test_study_identities.py::test_face_pngs_draw_each_identity_with_its_appearance": f"{_SECONDS}: 7.4",
    "tests/correct/test_collision.py::test_compiled_detection_equals_the_array_reference_on_ga_faces": f"{_SECONDS}: 5.3",
    "tests/correct/test_correct.py::test_interpenetration_before_and_after_on_ga_faces": f"{_SECONDS}: 11.3",
    "tests/correct/test_reach.py::test_no_interpenetration_or_lid_crossing_added_on_ga_faces": f"{_SECONDS}: 9.5",
    "tests/model/test_gltf.py::test_model_glb_without_correctives_has_shape_targets_only": f"{_SECONDS}: 3.4",
    "tests/model/test_ict.py::test_every_one_hot_reproduces_its_obj": f"{_SECONDS}: 12.4",
    "tests/model/test_model_hash.py::test_a_cut_neutral_mesh_is_named_against_the_pinned_manifest": f"{_SECONDS}: 3.8",
    "tests/render/test_clip.py::test_frames_are_the_curves_faces_and_the_same_every_time": f"{_SECONDS}: 32",
    "tests/render/test_cli.py::test_identities_render_with_their_appearance": f"{_SECONDS}: 5.5",
    "tests/render/test_cli.py::test_render_rows_of_a_csv_with_options": f"{_SECONDS}: 3.2",
    "tests/render/test_wrinkle_strength.py::test_wrinkle_strength_scales_the_furrows_and_leaves_unstrained_skin_alone": f"{_SECONDS}: 14.5 (paints a texture; load 13)",
    "tests/simulate/test_backends.py::test_corrected_simulation_is_the_same_in_a_process_pool_and_on_dask": f"{_SECONDS}: 9.4",
    "tests/simulate/test_backends.py::test_process_pool_gives_the_local_numbers": f"{_SECONDS}: 2.6 (starts a process pool)",
    "tests/simulate/test_tidy_outputs.py::test_analysis_tables_are_long_with_identifier_headers": f"{_SECONDS}: 5.7",
    "tests/simulate/test_dynamic.py::test_cli_simulate_dynamic": f"{_SECONDS}: 8.2 (three simulations and a figure; load 11)",
    "tests/simulate/test_dynamic.py::test_held_timing_converges_like_the_static_run": f"{_SECONDS}: 4.5 (load 11)",
    "tests/simulate/test_dynamic.py::test_cli_simulate_dynamic_errors": f"{_SECONDS}: 3.2 (load 11)",
    "tests/study/test_export_r.py::test_every_analysis_table_reads_in_r_as_written": f"{_SECONDS}: 5.6 (R)",
    "tests/study/test_export_r.py::test_every_export_table_reads_in_r_with_its_types": f"{_SECONDS}: 3.0 (R)",
    "tests/study/test_simulate_study.py::test_emogen_analyse_reads_a_study_of_evolve_and_categorise_blocks": f"{_SECONDS}: 29.2",
    "tests/study/test_simulate_study.py::test_own_faces_are_labelled_better_and_not_with_shuffled_prototypes": f"{_SECONDS}: 52.1",
    "tests/study/test_simulate_study.py::test_the_same_seed_gives_the_same_data": f"{_SECONDS}: 10.8",
    "tests/study/test_simulate_study.py::test_two_workers_run_every_participant": f"{_SECONDS}: 6.9",
    "tests/study/test_block_order.py::test_a_fixed_block_order_is_reported_as_confounded": f"{_SECONDS}: 4.5",
    "tests/study/test_block_order.py::test_example_design_balances_identity_over_block_positions": f"{_SECONDS}: 15.0",
    "tests/study/test_first_wave.py::test_a_concurrent_wave_without_a_pool_gets_only_fallback_faces": f"{_SECONDS}: 6.6",
    "tests/study/test_first_wave.py::test_a_pool_from_a_pilot_gives_the_first_wave_scored_others_faces": f"{_SECONDS}: 6.8",
    "tests/study/test_retest.py::test_between_and_within_session_icc_recover_planted_values": f"{_SECONDS}: 2.6",
    "tests/study/test_retest.py::test_simulated_retest_of_20_participants": f"{_SECONDS}: 41.2",
    "tests/study/test_tidy_export.py::test_csv_export_keeps_seeds_exact_for_r_and_times_with_their_zone": f"{_SECONDS}: 3.3 (R)",
    "tests/tasks/test_gsp_analysis.py::test_each_aggregate_lands_on_the_planted_prototype": f"{_SECONDS}: 13.8 (40 simulated participants)",
    "tests/tasks/test_gsp_analysis.py::test_chains_converge_and_the_concepts_separate": f"{_SECONDS}: 13.8 (its fixture, shared)",
    "tests/test_architecture.py::test_the_core_never_imports_the_web_framework": f"{_SECONDS}: 3.2 (a fresh interpreter)",
    "tests/test_cli_errors.py::test_no_colour_with_no_color_set": f"{_SECONDS}: 3.1 (a fresh interpreter)",
    "tests/test_cli_json.py::test_power_json_matches_its_files_and_keeps_assumptions_on_stderr": f"{_SECONDS}: 3.0",
    "tests/test_leftovers.py::test_a_download_is_private_while_it_exists": f"{_SECONDS}: 3.2 (a child process)",
    "tests/test_metrics.py::test_vertex_rms_matches_a_plain_loop_on_the_real_model": f"{_SECONDS}: 3.3",
    "tests/web/test_api.py::test_participants_cannot_reach_researcher_data": f"{_SECONDS}: 10.8 (download child processes)",
    "tests/web/test_api.py::test_shown_and_stored_faces_carry_their_correctives": f"{_SECONDS}: 17.2",
    "tests/web/test_dashboard.py::test_every_table_downloads_as_csv_and_parquet": f"{_SECONDS}: 11.0 (download child processes)",
    "tests/web/test_exports.py::test_dashboard_csv_is_the_export_table": f"{_SECONDS}: 16.6 (download child processes)",
    "tests/web/test_js.py::test_js_types_match_the_openapi_schema": f"{_SECONDS}: 3.3 (tsc)",
    "tests/web/test_schemathesis.py::test_no_server_errors": f"{_SECONDS}: 10.5 (and runs on both databases)",
    "tests/web/test_security.py::test_csv_exports_are_formula_safe_and_parquet_keeps_raw_values": f"{_SECONDS}: 3.4 (download child processes)",
    # a second measurement: the fast tier as `make check` runs it
    "tests/analysis/test_analyse_people.py::test_a_study_of_categorise_blocks_only_is_analysed": f"{_PARALLEL}: 4.9",
    "tests/analysis/test_analyse_study.py::test_analyse_a_one_participant_export": f"{_PARALLEL}: 6.0",
    "tests/analysis/test_categorisation_section.py::test_the_older_call_with_a_responses_table": f"{_PARALLEL}: 6.6",
    "tests/analysis/test_categorisation_section.py::test_the_section_of_a_study_with_a_categorise_block": f"{_PARALLEL}: 11.2",
    "tests/analysis/test_cli.py::test_replicate_table_iii_reads_both_ways": f"{_PARALLEL}: 13.7",
    "tests/analysis/test_fields.py::test_clustering_recovers_two_planted_subpopulations": f"{_PARALLEL}: 23.2",
    "tests/analysis/test_fields.py::test_fields_section_writes_tables_and_skips_what_it_cannot": f"{_PARALLEL}: 11.2",
    "tests/analysis/test_figures.py::test_bar_and_curve_figures_hold_for_2_to_12_groups[2]": f"{_PARALLEL}: 11.6",
    "tests/analysis/test_figures.py::test_bar_and_curve_figures_hold_for_2_to_12_groups[8]": f"{_PARALLEL}: 18.0",
    "tests/analysis/test_figures.py::test_every_figure_in_each_format_png_at_300_dpi": f"{_PARALLEL}: 3.3",
    "tests/analysis/test_figures.py::test_separability_layout_holds_for_2_to_12_groups[12]": f"{_PARALLEL}: 4.5",
    "tests/analysis/test_figures.py::test_separability_layout_holds_for_2_to_12_groups[8]": f"{_PARALLEL}: 4.1",
    "tests/analysis/test_groups.py::test_false_positive_rates_at_alpha": f"{_PARALLEL}: 6.3",
    "tests/analysis/test_identity.py::test_decoding_without_emotion_information_is_at_chance": f"{_PARALLEL}: 5.7",
    "tests/analysis/test_identity.py::test_emotion_decodes_across_identities": f"{_PARALLEL}: 6.6",
    "tests/analysis/test_identity.py::test_identity_section_skips_one_identity_and_writes_tables": f"{_PARALLEL}: 7.7",
    "tests/analysis/test_noise_calibration.py::test_a_noiseless_null_flags_noisy_choosers": f"{_PARALLEL}: 7.8",
    "tests/analysis/test_noise_calibration.py::test_latent_target_test_with_choice_noise": f"{_PARALLEL}: 7.5",
    "tests/analysis/test_noise_calibration.py::test_one_shared_target_is_flagged_at_most_at_alpha[0.05]": f"{_PARALLEL}: 12.5",
    "tests/analysis/test_noise_calibration.py::test_one_shared_target_is_flagged_at_most_at_alpha[0.0]": f"{_PARALLEL}: 9.4",
    "tests/analysis/test_noise_calibration.py::test_one_shared_target_is_flagged_at_most_at_alpha[0.1]": f"{_PARALLEL}: 7.4",
    "tests/analysis/test_noise_empirical.py::test_participants_own_prototypes_are_flagged": f"{_PARALLEL}: 3.4",
    "tests/analysis/test_power.py::test_identical_groups_reject_at_alpha_up_to_n_100": f"{_PARALLEL}: 3.6",
    "tests/analysis/test_power.py::test_intensity_needs_an_intensity_aware_statistic": f"{_PARALLEL}: 3.6",
    "tests/analysis/test_quality.py::test_position_bias_is_calibrated_under_uniform_picks": f"{_PARALLEL}: 6.0",
    "tests/analysis/test_reliability.py::test_interval_covers_a_known_icc[40]": f"{_PARALLEL}: 3.4",
    "tests/analysis/test_replication_findings.py::test_std_ed_geometry_is_misled_by_a_noisy_low_variance_component": f"{_PARALLEL}: 4.2",
    "tests/analysis/test_separability.py::test_identical_groups_are_lumped_and_the_third_found": f"{_PARALLEL}: 4.6",
    "tests/analysis/test_simulated_study.py::test_same_seed_same_study": f"{_PARALLEL}: 3.1",
    "tests/simulate/test_sweep.py::test_runs_resumes_and_reruns_only_changed_cells": f"{_PARALLEL}: 3.4",
    "tests/study/test_export_r.py::test_the_r_lines_of_the_data_dictionary_append_incremental_exports[sqlite]": f"{_PARALLEL}: 5.8",
    "tests/study/test_export_replay.py::test_head_is_alembics_head_and_a_current_database_opens_without_alembic": f"{_PARALLEL}: 5.5",
    "tests/study/test_export_stream.py::test_chunked_export_holds_what_one_table_holds[sqlite-csv]": f"{_PARALLEL}: 10.5",
    "tests/study/test_export_stream.py::test_chunked_export_holds_what_one_table_holds[sqlite-parquet]": f"{_PARALLEL}: 4.9",
    "tests/study/test_replay_export.py::test_exported_sessions_replay_exactly[sqlite-csv]": f"{_PARALLEL}: 5.7",
    "tests/study/test_replay_rounding.py::test_an_export_off_by_a_few_ulps_replays_and_1e6_does_not[csv]": f"{_PARALLEL}: 7.5",
    "tests/study/test_replay_rounding.py::test_an_export_off_by_a_few_ulps_replays_and_1e6_does_not[parquet]": f"{_PARALLEL}: 3.6",
    "tests/study/test_tidy_export.py::test_an_empty_export_has_the_schema_of_a_full_one[sqlite]": f"{_PARALLEL}: 4.0",
    "tests/study/test_validation_kit.py::test_validation_study_shows_every_stimulus_to_every_rater": f"{_PARALLEL}: 6.1",
    "tests/test_cli_errors.py::test_serve_with_an_unreachable_postgresql_server_is_one_line": f"{_PARALLEL}: 5.2",
    "tests/test_cli_startup.py::test_reading_a_trials_solver_and_exporting_load_no_compiled_correction": f"{_PARALLEL}: 3.3",
    "tests/web/test_hardening.py::test_faces_of_earlier_generations_are_not_served[sqlite]": f"{_PARALLEL}: 7.7",
    "tests/web/test_lab_room.py::test_a_room_of_60_behind_one_address_starts_and_a_flood_is_still_refused": f"{_PARALLEL}: 3.1",
    "tests/web/test_security.py::test_the_researcher_token_is_never_logged": f"{_PARALLEL}: 30.4",
    "tests/web/test_dynamic_view.py::test_the_page_is_sent_what_the_records_play": f"{_SECONDS}: 23.8",
    "tests/tasks/test_dynamic_evolve.py::test_a_dynamic_block_is_checked_and_served": f"{_SECONDS}: 7.7",
    "tests/tasks/test_dynamic_timing.py::test_a_planted_timing_difference_is_found": f"{_SECONDS}: 100 (30 simulated dynamic participants, load ~17)",
    "tests/tasks/test_dynamic_timing.py::test_the_report_shows_fearful_peaking_before_sad": f"{_SECONDS}: its fixture, shared",
    "tests/tasks/test_dynamic_timing.py::test_shared_timing_is_not_flagged": f"{_SECONDS}: 45 (12 simulated dynamic participants, load ~17)",
    "tests/tasks/test_dynamic_prototypes.py::test_each_participants_animation_is_their_final_face_as_render_clip_draws_it": f"{_SECONDS}: 77 (+288 s fixture: a corrected simulated study drawn; load ~30)",
    "tests/tasks/test_dynamic_prototypes.py::test_a_drawing_that_fails_says_why_and_keeps_the_analysis": f"{_SECONDS}: 8.1 (and the fixture above, load ~30)",
}

_KEYS = "idempotency keys: a repeated key is one step, on each backend's transactions"
_WORKERS = "two workers (stores) on one database: each backend's locking"
_TYPES = "the export reads each backend's column types and timestamps"

#: Run on SQLite and PostgreSQL (the rest of the database tests: SQLite only, issue #38).
BOTH_DATABASES: dict[str, str] = {
    "tests/study/test_sessions.py::test_whole_session_stores_every_generation_and_selection": "every record of a session written and read back",
    "tests/study/test_sessions.py::test_state_is_committed_before_answering_and_survives_a_new_server": "committed before answering: a second store reads it",
    "tests/study/test_sessions.py::test_repeated_key_is_one_step_and_stale_request_conflicts": _KEYS,
    "tests/study/test_sessions.py::test_concurrent_double_submissions_make_one_generation": "concurrent steps: each backend's locking",
    "tests/study/test_sessions.py::test_invalid_selections_leave_no_trace": "a refused step rolls back on each backend",
    "tests/study/test_sessions.py::test_correct_setting_decides_the_corrective_columns": "the stored weight columns follow the config on each backend",
    "tests/study/test_step_path.py": _WORKERS,
    "tests/study/test_workers.py": _WORKERS,
    "tests/tasks/test_gsp_chains.py": "GSP chains shared by sessions: each backend's row locks",
    "tests/study/test_counterbalance.py::test_concurrent_arrivals_in_two_workers_stay_balanced": _WORKERS,
    "tests/study/test_versions.py::test_a_retried_create_gets_the_same_session": "an idempotent create on each backend",
    "tests/study/test_categorise.py::test_a_mixed_study_shows_own_faces_and_stores_every_answer": "categorise answers stored and read back",
    "tests/study/test_categorise.py::test_others_faces_come_from_completed_sessions_balanced_over_labels": "the query that picks others' faces",
    "tests/study/test_categorise.py::test_wrong_answers_are_refused_and_a_repeated_key_stores_one": _KEYS,
    "tests/study/test_export_replay.py::test_migrations_are_idempotent_and_match_the_models": "Alembic on each backend",
    "tests/study/test_export_replay.py::test_export_holds_every_generation_and_selection": _TYPES,
    "tests/study/test_tidy_export.py::test_parquet_export_is_typed_and_carries_its_provenance": _TYPES,
    "tests/study/test_tidy_export.py::test_csv_export_keeps_seeds_exact_for_r_and_times_with_their_zone": _TYPES,
    "tests/study/test_export_stream.py::test_incremental_exports_appended_hold_each_completed_session_once": "chunked reads and `since` on each backend's timestamps",
    "tests/web/test_fault.py": "SIGKILL and retries against each backend, 1 and 2 workers",
    "tests/web/test_gsp_fault.py": "SIGKILL and retries against each backend, 1 and 2 workers",
    "tests/web/test_storage_faults.py": "storage faults of each backend",
    "tests/web/test_schemathesis.py": "the API fuzzed on each backend (issue #38 keeps it on both)",
}

#: Test files whose tests download exports: the server writes emogen-download-* folders in /tmp,
#: and test_exports and test_leftovers assert on every such folder there. Under pytest-xdist
#: their tests take one lock (tests/conftest.py), so no two of them run at once.
DOWNLOADS: frozenset[str] = frozenset(
    {
        "tests/test_leftovers.py",
        "tests/web/test_api.py",
        "tests/web/test_dashboard.py",
        "tests/web/test_exports.py",
        "tests/web/test_hardening.py",
        "tests/web/test_security.py",
    }
)
