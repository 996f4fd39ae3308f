#!/usr/bin/env bash
# Re-runs every committed result under results/ with the command in its README, into a scratch
# directory, and compares each committed file byte for byte (wall-clock files excepted:
# timings.csv). Prints one line per result and exits 1 if any file differs.
#
#   scripts/reproduce-results.sh [--update] [--only NAME,...] [--with-training] [BIN]
#
# --update writes what it re-ran over the committed files instead of comparing (the commit that
# changes behaviour re-runs its results so), READMEs and .gitignore files kept. BIN defaults to target/release/bkpbs. The PPO training run (results/rl-ppo's learning curve
# and policy, ~45 min on 2 cores) is re-run only with --with-training; its evaluation campaigns
# always are. --only re-runs just the named results (the names it prints, e.g.
# long-run-learned,calibration-lateral): for a change whose reach is known, as a profile-only one.
set -euo pipefail
cd "$(dirname "$0")/.."

with_training=0
update=0
only=""
while [ $# -gt 0 ]; do
    case "$1" in
        --update) update=1 ;;
        --with-training) with_training=1 ;;
        --only) only=",${2:?--only needs a list of result names},"; shift ;;
        *) break ;;
    esac
    shift
done
BIN=$(realpath "${1:-target/release/bkpbs}")
[ -x "$BIN" ] || { echo "reproduce: error: $BIN is not an executable (cargo build --release)" >&2; exit 1; }
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
failed=0

# agreed: what a result that passed is: identical to the committed files, or (--update) written
# over them.
agreed() {
    if [ $update = 1 ]; then echo updated; else echo identical; fi
}

# wanted NAME: whether this run re-runs result NAME (every result without --only); a NAME
# GROUP/PART is also wanted with GROUP.
wanted() {
    [ -z "$only" ] || [[ "$only" == *",$1,"* ]] || [[ "$only" == *",${1%%/*},"* ]]
}

# compare DIR_COMMITTED DIR_NEW: every committed file but timings.csv and README.md must match.
# With --update, DIR_NEW's files replace DIR_COMMITTED's (its README.md and .gitignore kept).
compare() {
    local committed=$1 new=$2 bad=0
    if [ $update = 1 ]; then
        mkdir -p "$committed"
        find "$committed" -mindepth 1 -maxdepth 1 ! -name README.md ! -name .gitignore -exec rm -rf {} +
        cp -a "$new/." "$committed/"
        return 0
    fi
    while IFS= read -r f; do
        case "$f" in */timings.csv | */README.md | */.gitignore | ./plots/*) continue ;; esac
        if ! cmp -s "$committed/$f" "$new/$f"; then
            echo "  differs: $committed/$f"
            bad=1
        fi
    done < <(cd "$committed" && find . -type f | sort)
    return $bad
}

# same_files NAME COMMITTED_DIR NEW_DIR FILE...: the named files of the two directories agree.
same_files() {
    local name=$1 committed=$2 new=$3 bad=0
    shift 3
    for f in "$@"; do
        if [ $update = 1 ]; then cp "$new/$f" "$committed/$f"; continue; fi
        cmp -s "$committed/$f" "$new/$f" || { echo "  differs: $committed/$f"; bad=1; }
    done
    if [ $bad = 0 ]; then echo "$name: $(agreed) ($((SECONDS - start)) s)"; else echo "$name: DIFFERS"; failed=1; fi
}

# result NAME COMMITTED_DIR: runs the rest of the line (with $OUT as its --out), then compares.
result() {
    local name=$1 committed=$2
    shift 2
    wanted "$name" || return 0
    local out="$scratch/$name"
    mkdir -p "$(dirname "$out")"
    local start=$SECONDS
    # $versus: set by result_versus (dynamic scope), empty otherwise.
    if ! "$@" --out "$out" >"$scratch/$name.log" 2>&1 \
        || { [ -n "${versus:-}" ] && ! "$BIN" report "$out" --versus "$versus" >>"$scratch/$name.log" 2>&1; }; then
        echo "$name: FAILED to run (log below)"; tail -5 "$scratch/$name.log"; failed=1; return
    fi
    rm -rf "$out/episodes"
    if compare "$committed" "$out"; then
        echo "$name: $(agreed) ($((SECONDS - start)) s)"
    else
        echo "$name: DIFFERS"; failed=1
    fi
}

# result_versus NAME COMMITTED_DIR REFERENCES: as result, then `report --versus REFERENCES` on it.
result_versus() {
    local name=$1 committed=$2 versus=$3
    shift 3
    result "$name" "$committed" "$@"
}

result paper-grid results/paper-grid "$BIN" campaign
result_versus safety-on results/safety/shield-on bk-mastar "$BIN" campaign --planners bk-mastar,bk-pbs \
    --alphas 0.4,0.6,0.8 --lambdas 2500,3000 --seeds 25
result_versus safety-off results/safety/shield-off bk-mastar "$BIN" campaign --planners bk-mastar,bk-pbs \
    --alphas 0.4,0.6,0.8 --lambdas 2500,3000 --seeds 25 --config results/safety/shield-off.toml
result three-lane results/networks/three-lane "$BIN" campaign --config results/networks/three-lane.toml \
    --planners sumo,idm-mobil,bk-mastar,bk-pbs --alphas 0.4,0.8 --lambdas 2500,3000 --seeds 5
result corridor results/networks/corridor "$BIN" campaign --config results/networks/corridor.toml \
    --planners sumo,idm-mobil,bk-mastar,bk-pbs --alphas 0.4,0.8 --lambdas 5000,6000 --seeds 5 --steps 1000
result profiles-matched results/profiles/matched "$BIN" campaign --config results/profiles/matched.toml \
    --hdv-profiles sumo-safe,paper,heterogeneous,krauss,eidm --alphas 0.4,0.8 --lambdas 3000 --seeds 10
result profiles-mismatch results/profiles/mismatch "$BIN" campaign --config results/profiles/mismatch.toml \
    --alphas 0.4,0.8 --lambdas 3000 --seeds 10
result profiles-paper-grid results/profiles/paper-grid "$BIN" campaign --config results/profiles/matched.toml \
    --hdv-profiles paper --seeds 20
result rl-shield-off results/rl-ppo/shield-off "$BIN" campaign --planners rl-ppo --seeds 10
result rl-shield-on results/rl-ppo/shield-on "$BIN" campaign --planners rl-ppo --seeds 10 \
    --config results/rl-ppo/shield-on.toml

# The SUMO-version study (results/sumo-versions): each half with a binary built against its SUMO,
# so a 1.28 build re-runs only its half: --only sumo-versions-1.28,sumo-versions-seeds-1.28.
case "$("$BIN" --version)" in
    *"SUMO 1.28.0"*)
        result sumo-versions-1.28 results/sumo-versions/1.28 "$BIN" campaign
        result sumo-versions-seeds-1.28 results/sumo-versions/seeds-0-9/1.28 "$BIN" campaign \
            --alphas 0.5 --lambdas 3000 --seeds 10 ;;
    *"SUMO 1.15.0"*)
        result sumo-versions-seeds-1.15 results/sumo-versions/seeds-0-9/1.15 "$BIN" campaign \
            --alphas 0.5 --lambdas 3000 --seeds 10 ;;
esac

# The version study's pairings, from the committed campaigns of both halves (whichever ran).
if wanted sumo-versions-pairs; then
    start=$SECONDS
    mkdir -p "$scratch/pairs/seeds-0-9"
    metrics=system_delay_s,mean_delay_s,arrived,stranded,controllable_crashed
    python3 results/long-run/predictor_pairs.py results/sumo-versions/1.28 results/paper-grid \
        $metrics > "$scratch/pairs/pairs.md"
    python3 results/long-run/predictor_pairs.py results/sumo-versions/seeds-0-9/1.28 \
        results/sumo-versions/seeds-0-9/1.15 $metrics > "$scratch/pairs/seeds-0-9/pairs.md"
    bad=0
    for f in pairs.md seeds-0-9/pairs.md; do
        if [ $update = 1 ]; then
            cp "$scratch/pairs/$f" "results/sumo-versions/$f"
        elif ! cmp -s "$scratch/pairs/$f" "results/sumo-versions/$f"; then
            echo "  differs: results/sumo-versions/$f"; bad=1
        fi
    done
    if [ $bad = 0 ]; then
        echo "sumo-versions-pairs: $(agreed) ($((SECONDS - start)) s)"
    else
        echo "sumo-versions-pairs: DIFFERS"; failed=1
    fi
fi

# The long runs (~35 min on 2 cores): each campaign, then its paired report.
long="--hdv-profiles sumo-safe,paper --alphas 0.4,0.6,0.8 --steps 1500"
# shellcheck disable=SC2086
result_versus long-run-learned results/long-run/learned idm-mobil,bk-mastar "$BIN" campaign --config results/long-run/long-run.toml \
    $long --lambdas 2500,3000,3500 --seeds 10 --seed-base 20000
# shellcheck disable=SC2086
result_versus long-run-predictors results/long-run/predictors bk-pbs+constant "$BIN" campaign \
    --config results/long-run/long-run.toml --planners bk-pbs --predictors learned,constant $long --lambdas 3000 \
    --seeds 10 --seed-base 20000
# shellcheck disable=SC2086
result_versus long-run-fresh results/long-run/fresh idm-mobil,bk-mastar "$BIN" campaign --config results/long-run/long-run.toml \
    --planners idm-mobil,bk-mastar,bk-pbs $long --lambdas 3000 --seeds 30 --seed-base 40000
# shellcheck disable=SC2086
result_versus long-run-unseen results/long-run/unseen idm-mobil,bk-mastar "$BIN" campaign --config results/long-run/long-run.toml \
    --planners idm-mobil,bk-mastar,bk-pbs $long --lambdas 3000 --seeds 30 --seed-base 50000

# The study on SUMO's own game scenarios (results/scenarios, ~20 min on 2 cores: its episodes' wall times sum to 39 minutes): copies of the
# games as a user brings them, then the campaign over A10KW and ramp, then one merge's figures.
if wanted scenarios || wanted scenarios-plots; then
    scripts/scenario-games.sh target/scenario-games
fi
games=target/scenario-games
result scenarios results/scenarios "$BIN" campaign --sumocfg $games/A10KW-motorway.sumocfg,$games/ramp.sumocfg \
    --planners bk-pbs,bk-mastar,idm-mobil,sumo,rl-ppo --alphas 0.3,0.6 --seeds 3 --seed-base 100
if wanted scenarios-plots; then
    start=$SECONDS
    plots="$scratch/scenario-plots/bk-pbs_ramp_a0.6_s100"
    if "$BIN" episode --sumocfg $games/ramp.sumocfg --planner bk-pbs --alpha 0.6 --seed 100 \
            --trajectories --out "$plots" >/dev/null 2>&1 \
        && "$BIN" plot "$plots/trajectories/gneE7" >/dev/null 2>&1 \
        && rm "$plots/trajectories/gneE7/trajectories.csv" "$plots/trajectories/gneE7/"*.svg \
            "$plots/timing.csv" "$plots/sumo_options.txt" \
        && compare results/scenarios/plots "$scratch/scenario-plots"; then
        echo "scenarios-plots: $(agreed) ($((SECONDS - start)) s)"
    else
        echo "scenarios-plots: DIFFERS"; failed=1
    fi
fi

# The merge-layout study (results/layouts, ~11 min on 2 cores): every layout of
# sumo_net/layouts, each planner against SUMO alone on the same seeds, paired per region and
# entry.
layouts="two-lane-ramp two-lane-gain lane-drop left-lane-drop nose-merge left-side-ramp two-ramps-alongside cloverleaf trucks-beside-merge"
layout_cfgs=$(for l in $layouts; do printf 'sumo_net/layouts/%s/%s.sumocfg,' "$l" "$l"; done)
result_versus layouts results/layouts sumo "$BIN" campaign --sumocfg "${layout_cfgs%,}" \
    --planners bk-pbs,bk-mastar,idm-mobil,sumo --alphas 0.3,0.6 --seeds 10 --seed-base 1000

# The learned parts trained on SUMO's ramp game against the paper-trained ones
# (results/learned-per-scenario, ~15 min on 2 cores): b_θ and the RL policy of
# models/scenarios/ramp, seeds 500-519 at α 0.6, then the paired tables.
ramp_game=target/scenario-games/ramp.sumocfg
lps=results/learned-per-scenario
lps_grid="--sumocfg $ramp_game --alphas 0.6 --seeds 20 --seed-base 500"
if wanted learned-per-scenario && [ ! -f "$ramp_game" ]; then
    scripts/scenario-games.sh target/scenario-games
fi
# shellcheck disable=SC2086
result learned-per-scenario/paper-trained $lps/paper-trained "$BIN" campaign $lps_grid --planners bk-pbs \
    --predictors learned,constant
# shellcheck disable=SC2086
result learned-per-scenario/ramp-trained $lps/ramp-trained "$BIN" campaign $lps_grid --planners bk-pbs,rl-ppo \
    --config $lps/ramp-trained.toml
# shellcheck disable=SC2086
result learned-per-scenario/baselines $lps/baselines "$BIN" campaign $lps_grid --planners sumo,rl-ppo
# shellcheck disable=SC2086
result learned-per-scenario/rl-shield-on/paper $lps/rl-shield-on/paper "$BIN" campaign $lps_grid --planners rl-ppo \
    --config results/rl-ppo/shield-on.toml
# shellcheck disable=SC2086
result learned-per-scenario/rl-shield-on/ramp-trained $lps/rl-shield-on/ramp-trained "$BIN" campaign $lps_grid --planners rl-ppo \
    --config $lps/ramp-trained-shield-on.toml
if wanted learned-per-scenario; then
    start=$SECONDS
    python3 $lps/pairs.py "$scratch/learned-per-scenario" > "$scratch/learned-per-scenario/pairs.md"
    same_files learned-per-scenario-pairs $lps "$scratch/learned-per-scenario" pairs.md
    # b_θ's accuracy on fresh episodes of the game (seeds 90000-90003), paper- and ramp-trained.
    start=$SECONDS
    eval_dir="$scratch/learned-per-scenario/predictor"
    mkdir -p "$eval_dir"
    "$BIN" collect --sumocfg $ramp_game --episodes 4 --steps 2000 --seed-base 90000 \
        --out "$eval_dir/eval.bin" >/dev/null 2>&1
    "$BIN" eval-predictor --data "$eval_dir/eval.bin" >"$eval_dir/paper-trained.txt" 2>/dev/null
    "$BIN" eval-predictor --data "$eval_dir/eval.bin" --model models/scenarios/ramp/gcn-conditioned.json \
        >"$eval_dir/ramp-trained.txt" 2>/dev/null
    rm "$eval_dir/eval.bin"
    same_files learned-per-scenario-predictor $lps/predictor "$eval_dir" paper-trained.txt ramp-trained.txt
fi

# The paper grid's traced episode and its figures.
if wanted paper-grid-plots; then
    start=$SECONDS
    plots="$scratch/plots/bk-pbs_a0.5_l3000_s0"
    if "$BIN" episode --planner bk-pbs --alpha 0.5 --lambda 3000 --seed 0 --trajectories --out "$plots" >/dev/null 2>&1 \
        && "$BIN" plot "$plots" >/dev/null 2>&1 && compare results/paper-grid/plots "$scratch/plots"; then
        echo "paper-grid-plots: $(agreed) ($((SECONDS - start)) s)"
    else
        echo "paper-grid-plots: DIFFERS"; failed=1
    fi
fi

# The calibration matrix writes into its own directory beside the lateral evaluations.
if wanted calibration-matrix; then
    mkdir -p "$scratch/calibration"
    start=$SECONDS
    if "$BIN" calibrate --matrix --out "$scratch/calibration" >"$scratch/calibration.log" 2>&1; then
        same_files calibration-matrix results/calibration "$scratch/calibration" \
            longitudinal_matrix.csv longitudinal_matrix.md longitudinal_matrix.png longitudinal_matrix.svg
    else
        echo "calibration-matrix: FAILED to run"; tail -5 "$scratch/calibration.log"; failed=1
    fi
fi

if wanted calibration-lateral; then
    start=$SECONDS
    bad=0
    for p in sumo-safe paper heterogeneous krauss eidm; do
        "$BIN" collect --hdv-profile $p --episodes 100 --seed-base 90000 --out "$scratch/eval-$p.bin" >/dev/null 2>&1
        "$BIN" eval-predictor --data "$scratch/eval-$p.bin" >"$scratch/lateral-$p.txt" 2>/dev/null
        [ $update = 1 ] && cp "$scratch/lateral-$p.txt" "results/calibration/lateral/$p.txt"
        cmp -s "results/calibration/lateral/$p.txt" "$scratch/lateral-$p.txt" || { echo "  differs: lateral/$p.txt"; bad=1; }
        for q in paper heterogeneous krauss eidm; do
            "$BIN" eval-predictor --model models/profiles/$q/gcn-conditioned.json --data "$scratch/eval-$p.bin" \
                >"$scratch/lateral-$q-$p.txt" 2>/dev/null
            [ $update = 1 ] && cp "$scratch/lateral-$q-$p.txt" "results/calibration/lateral/trained-on-$q/$p.txt"
            cmp -s "results/calibration/lateral/trained-on-$q/$p.txt" "$scratch/lateral-$q-$p.txt" \
                || { echo "  differs: lateral/trained-on-$q/$p.txt"; bad=1; }
        done
        rm -f "$scratch/eval-$p.bin"
    done
    if [ $bad = 0 ]; then echo "calibration-lateral: $(agreed) ($((SECONDS - start)) s)"; else echo "calibration-lateral: DIFFERS"; failed=1; fi
fi

if [ $with_training = 1 ] && wanted rl-training; then
    start=$SECONDS
    "$BIN" train-rl --out "$scratch/rl-train" --steps 10000000 >"$scratch/rl-train.log" 2>&1
    same_files rl-training results/rl-ppo "$scratch/rl-train" \
        learning_curve.csv learning_curve.png learning_curve.svg evaluation.csv
else
    echo "rl-training: skipped (--with-training re-runs it, ~45 min)"
fi

exit $failed
