# A corrected study recorded with rig 2 (emogen/data/ict_rig_2.toml: reach shapes version 1),
# for tests/study/test_recorded_rig1.py. Made at dd91198 (rig 2 the default) with the study
# config below.
cat > /tmp/rig2.toml <<'TOML'
name = "recorded-with-rig-2"
seed = 4242
emotions = ["angry", "happy", "fearful"]
identities = ["female-dark-v3"]
correct = true

[ga]
generations = 3
min_selections = 1
max_selections = 5
TOML
emogen study simulate /tmp/rig2.toml --participants 2 --seed 42 \
  --database-url sqlite:///tests/data/study_rig2.sqlite
