# A corrected study recorded with rig 1 (emogen/data/ict_rig_1.toml, before the reach shapes),
# for tests/study/test_recorded_rig1.py. Made at 69649b0 with the study config below.
cat > /tmp/rig1.toml <<'TOML'
name = "recorded-with-rig-1"
seed = 4242
emotions = ["angry", "happy"]
identities = ["female-dark"]
correct = true

[ga]
generations = 3
min_selections = 1
max_selections = 5
TOML
emogen study simulate /tmp/rig1.toml --participants 2 --seed 42 \
  --database-url sqlite:///tests/data/study_rig1.sqlite
