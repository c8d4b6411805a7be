#!/usr/bin/env bash
# Writes docs/random.md: the kernel against the reference limit on COUNT scenes drawn at random
# (seed SCENE_SEED), none of them shipped. Each scene draws:
#   classes       2 (three times in four) or 3, each a named material (coal, sandstone,
#                 roof_sandstone, sandy_mudstone; distinct) or, for four scenes in ten, each
#                 class its own: density 1200-2800 kg/m^3, modulus 3-40 GPa (log-uniform),
#                 Poisson 0.10-0.35; priors from {1, 1, 3, 0.3, 9}
#   sizes         one radius range for every class: R_min 8-60 mm (log-uniform), R_max / R_min
#                 e^0.3-e^1.5
#   speeds        u_min 0.5-3 m/s, u_max u_min + 1-5 m/s, as a speed range or (three in ten)
#                 as the drop heights that give them
#   contact law   hertz (two in seven) or hunt_crossley, lankarani_nikravesh, flores, gonthier,
#                 tsuji with e 0.3-0.9
#   sensor        26.7, 40, 50, 100 or 200 kS/s; effective mass 20-200 kg; 5-60 counts per
#                 m/s^2 on a 16-bit ADC; noise 1, 4, 4, 10 or 20 counts RMS
#   chain         (three in ten) an accelerometer band at 0.25-0.45 of the sample rate, damping
#                 0.3-0.8, identified to 0.5 % / 1 %; (three in ten) one or two beam modes of
#                 120-2100 Hz, damping 0.005-0.04, gain 0.02-0.15, identified to 0.2 % / 15 % / 5 %
# and is evaluated by `host-sim evaluate --json` (N impacts per class, seed SEED), JOBS at a
# time, against the targets of docs/grid.md. Two causes are named where a row misses:
#   saturated  more than 1 % of the impacts are rejected as saturated: clipped at the ADC's full
#              scale and not measured from their flanks (the kernel measures a clipped pulse
#              of the Hertz law or a restitution-parametrised one from its flanks, on a rigid
#              beam and behind a chain; one whose flanks it cannot read is Saturated). The table also gives the share of the impacts the
#              scene build predicts at full scale (it warns above 1 %).
#   faint  more than 5 % of the impacts peak below 10 times the force noise the detector sees
#          (`evaluate`'s table "by peak over noise")
# Usage: bash docs/random-table.sh [N] [SEED] [COUNT] [SCENE_SEED] [JOBS]   (from the
# repository root; needs python3; N 2000, SEED 1, COUNT 60, SCENE_SEED 1, JOBS 2 by default)
set -euo pipefail
n=${1:-2000}
seed=${2:-1}
count=${3:-60}
scene_seed=${4:-1}
jobs=${5:-2}
cargo build --release -q -p host-sim
bin=$(realpath "${CARGO_TARGET_DIR:-target}")/release/host-sim
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

python3 - "$work" "$count" "$scene_seed" <<'EOF'
import math, os, random, sys
work, count, scene_seed = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
rnd = random.Random(scene_seed)
named = ["coal", "sandstone", "roof_sandstone", "sandy_mudstone"]
laws = ["hertz", "hertz", "hunt_crossley", "lankarani_nikravesh", "flores", "gonthier", "tsuji"]
for i in range(count):
    name = "r%d" % i
    k = rnd.choice([2, 2, 2, 3])
    r_min = math.exp(rnd.uniform(math.log(0.008), math.log(0.06)))
    r_max = r_min * math.exp(rnd.uniform(0.3, 1.5))
    heights = rnd.random() < 0.3
    u_min = rnd.uniform(0.5, 3.0)
    u_max = u_min + rnd.uniform(1.0, 5.0)
    mats = rnd.sample(named, k) if rnd.random() < 0.6 else None
    s = 'name = "%s"\nplate = "carbon_steel"\n' % name
    for c in range(k):
        if mats:
            m = '"%s"' % mats[c]
        else:
            m = "{ density_kg_m3 = %.0f, modulus_pa = %.4g, poisson = %.2f }" % (
                rnd.uniform(1200, 2800), math.exp(rnd.uniform(math.log(3e9), math.log(40e9))),
                rnd.uniform(0.1, 0.35))
        s += '\n[[classes]]\nname = "c%d"\nmaterial = %s\nradius_m = [%.4f, %.4f]\n' % (
            c, m, r_min, r_max)
        if heights:
            s += "drop_height_m = [%.3f, %.3f]\n" % (u_min**2 / 19.62, u_max**2 / 19.62)
        else:
            s += "speed_m_s = [%.2f, %.2f]\n" % (u_min, u_max)
        s += "prior = %.1f\n" % rnd.choice([1.0, 1.0, 3.0, 0.3, 9.0])
    law = rnd.choice(laws)
    s += '\n[contact]\nlaw = "%s"\n' % law
    e = rnd.uniform(0.3, 0.9)
    if law != "hertz":
        s += "restitution = %.2f\n" % e
    rate = rnd.choice([26667.0, 40000.0, 50000.0, 100000.0, 200000.0])
    noise = rnd.choice([1.0, 4.0, 4.0, 10.0, 20.0])
    s += ("\n[sensor]\nsample_rate_hz = %.1f\neffective_mass_kg = %.1f\ncounts_per_m_s2 = %.1f\n"
          "noise_rms_counts = %.1f\nadc_bits = 16\ndc_offset_counts = 0.0\n"
          "dc_drift_counts_per_s = 0.0\n") % (rate, rnd.uniform(20, 200), rnd.uniform(5, 60), noise)
    chain = []
    if rnd.random() < 0.3:
        s += "accelerometer = { frequency_hz = %.1f, damping_ratio = %.2f }\n" % (
            rnd.uniform(0.25, 0.45) * rate, rnd.uniform(0.3, 0.8))
        s += "accelerometer_tolerance = { frequency = 0.005, damping = 0.01 }\n"
        chain.append("band")
    if rnd.random() < 0.3:
        s += "chain_tolerance = { frequency = 0.002, damping = 0.15, gain = 0.05 }\n"
        modes = sorted(rnd.sample([120, 180, 300, 650, 900, 1500, 2100], rnd.choice([1, 2])))
        for f in modes:
            s += "\n[[sensor.beam_modes]]\nfrequency_hz = %.1f\ndamping_ratio = %.3f\ngain = %.3f\n" % (
                f, rnd.uniform(0.005, 0.04), rnd.uniform(0.02, 0.15))
        chain.append("modes")
    s += "\n[settings]\n"
    open(os.path.join(work, name + ".toml"), "w").write(s)
    law_e = law if law == "hertz" else "%s %.2f" % (law, e)
    print("\t".join([name, law_e, str(k), "%.0f-%.0f" % (1e3 * r_min, 1e3 * r_max),
                     "%g" % rate, "%g" % noise, "+".join(chain) or "rigid"]),
          file=open(os.path.join(work, "list.tsv"), "a"))
EOF

cut -f1 "$work/list.tsv" | xargs -P "$jobs" -I{} sh -c \
    '"$1" evaluate --scene "$2/$3.toml" --n "$4" --seed "$5" --json > "$2/$3.json" 2> "$2/$3.err" || true' \
    _ "$bin" "$work" {} "$n" "$seed"

python3 - "$work" "$n" "$seed" "$count" "$scene_seed" > docs/random.md <<'EOF'
import json, os, re, sys
sys.path.insert(0, "docs")
from targets import beats_reference, check, names, print_beaten, print_misses, print_refused, refusal  # noqa: E402
work, n, seed, count, scene_seed = sys.argv[1:6]
rows, misses, causes, refused, failed = [], {"forced choice": [], "confident errors": [], "calibration": []}, {}, [], []
beaten = []
for line in open(os.path.join(work, "list.tsv")):
    name, law_e, k, radii, rate, noise, chain = line.rstrip("\n").split("\t")
    err = open(os.path.join(work, name + ".err")).read()
    head = "| %s | %s | %s | %s | %s | %s | %s |" % (name, law_e, k, radii, rate, noise, chain)
    try:
        d = json.load(open(os.path.join(work, name + ".json")))
    except (OSError, ValueError):
        why = refusal(err)
        if why:
            refused.append(name)
            rows.append(head + " refused | | | | | | | | | %s |" % why)
        else:
            failed.append(name)
            rows.append(head + " failed | | | | | | | | | %s |" % err.strip().splitlines()[-1:])
        continue
    clip = re.search(r"ADC clipping: ([0-9.]+) %", err)
    clip = float(clip.group(1)) if clip else 0.0
    bins = d["by_peak_over_noise"]["bins"]
    impacts = sum(b["impacts"] for b in bins)
    faint = sum(b["impacts"] for b in bins if b["to"] is not None and b["to"] <= 10.0) / max(impacts, 1)
    fails, gap, se, worst_bin = check(d)
    if beats_reference(d):
        beaten.append(name)
    rel = d["reliability"]
    saturated = d["rejected_by_reason"].get("saturated", 0) / max(impacts, 1)
    cause = [c for c, hit in (("saturated", saturated > 0.01), ("faint", faint > 0.05)) if hit]
    for f in fails:
        misses[f].append(name)
    if fails:
        key = " and ".join(cause) or "neither"
        causes[key] = causes.get(key, 0) + 1
    rows.append(head + " %.1f | %.1f | %.1f | %.2f | %.2f | %+.2f ± %.2f | %.1f | %.2f | %.1f | %s |" % (
        clip, 100 * saturated, 100 * faint, 100 * d["forced_choice_accuracy"], 100 * d["reference"]["accuracy"],
        100 * gap, 100 * se, 100 * d["coverage"], 100 * d["confident_error_rate"],
        100 * rel["calibration_error_max"],
        (", ".join(fails) + (" (" + ", ".join(cause) + ")" if cause else "")) if fails else "met"))
total = len(rows) - len(refused) - len(failed)
print("# Scenes drawn at random\n")
print("`bash docs/random-table.sh %s %s %s %s` wrote this file: %s scenes drawn at random (scene" % (n, seed, count, scene_seed, count))
print("seed %s; the script's header says from what), none of them shipped, each evaluated by" % scene_seed)
print("`host-sim evaluate --n %s --seed %s --json` and held to the targets of `docs/grid.md`" % (n, seed))
print("(forced choice within 1 pp of the reference limit beyond two standard errors, confident")
print("errors at most 1 %, calibration within 2 pp beyond two standard errors in every bin of")
print("at least 200 verdicts). *clipping* is the share of the impacts the scene build predicts at")
print("the ADC's full scale, weighted by the classes' priors (it warns above 1 %); the kernel measures")
print("a clipped pulse of the Hertz law or of a restitution-parametrised one from its flanks, on a")
print("rigid beam and behind a chain, and *saturated* is the share of the evaluated impacts (n per class, whatever the")
print("priors) it rejects as saturated. A row that misses names its causes: *saturated* (more than")
print("1 % of the impacts rejected so) and *faint* (more than 5 % of the impacts peak below 10")
print("times the force noise the detector sees).\n")
print("## Misses\n")
print_misses(misses, total)
print_beaten(beaten, total)
print("- scenes that miss a target, by cause: %s" % (", ".join("%s %d" % kv for kv in sorted(causes.items())) or "none"))
print_refused(refused)
print("Failed to evaluate: %d%s" % (len(failed), names(failed)))
print("\n## Every scene\n")
print("| scene | law, e | classes | R (mm) | rate (Hz) | noise (counts) | chain | clipping (%) | saturated (%) | below 10 noise (%) | forced choice (%) | reference (%) | kernel - reference (pp) | coverage (%) | confident errors (%) | calibration error max (pp) | targets |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
print("\n".join(rows))
EOF
# Faint pulses: one scene whose small lumps peak near the detector's trigger.
faint=docs/faint/faint_rigid.toml
{
    echo
    echo "## Faint pulses"
    echo
    echo "\`$faint\` (three classes of small lumps, 11.6-21.7 mm, a rigid beam, 20 counts of noise:"
    echo "259 N of force noise) under \`host-sim evaluate --scene $faint --n $n --seed $seed\`. Its"
    echo "table \"by peak over noise\" bins the impacts by their simulated peak force over that"
    echo "noise. The detector starts a pulse at 6 noise RMS (\`trigger_sigmas\`): below that a pulse is"
    echo "found only when the noise lifts it, so its measured peak is biased up and its duration"
    echo "(the area over the peak) down. A pulse measured less than three standard deviations of"
    echo "its peak above the trigger (\`Measurement::trigger_margin\`) gets no \`Class\` verdict: it"
    echo "is \`Ambiguous\`, with its best class and posterior (22 of the 81 confident verdicts below"
    echo "6 noise RMS were wrong without that rule, 0.98 % of the scene's confident verdicts, at"
    echo "49.9 % coverage, at commit 7fef504). The reference counts each impact with the probability"
    echo "that a matched filter at the trigger's false-alarm rate finds it (\"found at the limit\"),"
    echo "where the kernel's detector triggers on one sample: most of the gap is the impacts the"
    echo "kernel misses (\"missed\"). Above the trigger the measurement's own second-order biases"
    echo "are taken out: the five samples' vertex bias in \`ln F_max\` (\`PeakFit::vertex_bias\`), the"
    echo "sum's \`-var / (2 S^2)\` in \`ln t_c\` (\`Detector::unbiased_sum\`), and the lift a pulse's own"
    echo "rising edge gave the baseline (\`Detector::baseline_before\`). What \`ln t_c\` keeps at 6-16"
    echo "noise RMS comes from the impacts that never trigger, whose samples lift the baseline as"
    echo "quiet ones do, and from the tail past the release."
    echo
    echo '```'
    "$bin" evaluate --scene "$faint" --n "$n" --seed "$seed" 2>&1 |
        sed -n '/^  forced-choice accuracy/p;/^  coverage (decided)/p;/^  confident-error rate/p;/^  ambiguous \//p;/^  reference limit/p;/^  found at the limit/p;/calibration error over/p;/^by peak/,/^$/p'
    echo '```'
} >> docs/random.md
echo "wrote docs/random.md" >&2
