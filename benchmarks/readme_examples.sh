#!/usr/bin/env bash
# Run every README example (and each command's --help) from the repository root, saving stdout,
# stderr, exit codes and written files under OUTDIR. Two such folders from two commits diff to
# show what a change did to the outputs (timestamps aside):
#   bash benchmarks/readme_examples.sh /tmp/a   # on commit A
#   bash benchmarks/readme_examples.sh /tmp/b   # on commit B
#   diff -r -I created_utc -I DTSTAMP /tmp/a /tmp/b
# Usage: readme_examples.sh OUTDIR
set -u
OUT=${1:?give a new output folder}
if [ -e "$OUT" ]; then echo "$OUT exists; give a new folder" >&2; exit 2; fi
mkdir -p "$OUT"
C=$PWD/catalogs
cd "$OUT"; mkdir -p figs simfigs
r() { local name=$1; shift; ucbplan "$@" >"$name.out" 2>"$name.err"; echo "rc=$?" >>"$name.err"; }
r plan plan $C/hm-cnc-simulated.yaml --site paranal --night 2040-02-15
r horizon horizon $C/hm-cnc-simulated.yaml
r horizon_json horizon $C/hm-cnc-simulated.yaml --format json
r horizon_plot horizon $C/fiducial-eccentric.yaml --plot horizon.png
r validate validate $C/hm-cnc-simulated.yaml $C/fiducial-eccentric.yaml
r validate_json validate $C/hm-cnc-simulated.yaml $C/fiducial-eccentric.yaml --format json
r ephem ephemeris $C/hm-cnc-simulated.yaml --start 2040-02-15T00:00 --end 2040-02-15T01:00 --anchor quadrature
r ephem_csv ephemeris $C/fiducial-eccentric.yaml --start 2040-02-15T00:00 --end 2040-02-15T00:30 --anchor zero-crossing --format csv
r plan2 plan $C/hm-cnc-simulated.yaml --site paranal --night 2040-02-15 -o blocks.ecsv --plot night.png
r plan3 plan $C/fiducial-eccentric.yaml --site paranal --night 2040-06-15 --nights 2 --mode fixed-u-pairs -o fixed.ecsv
r plan4 plan $C/hm-cnc-simulated.yaml --site lasilla --night 2040-03-01 --nights 2 --mode zero-crossing --format json
r exp_p2 export blocks.ecsv --to eso-p2 --acquisition 480 -o hmcnc_p2.json
r exp_tex export blocks.ecsv --to proposal --format latex -o technical.tex
r exp_prop export blocks.ecsv --to proposal --format ecsv
r exp_keck export blocks.ecsv --to keck-starlist
r exp_ics export blocks.ecsv --to ics -o cal.ics
r exp_ing export blocks.ecsv --to ing-cat
r exp_lco export blocks.ecsv --to lco
r feas feasibility $C/fiducial-eccentric.yaml --plot aps.png
r feas_json feasibility $C/hm-cnc-simulated.yaml --m1 0.55 --m2 0.27 --format json
r reduce reduce $C/fiducial-eccentric.yaml $C/fiducial-eccentric-velocities.csv --format json -o report.json --plots figs/ --em-prior prior.yaml --seed 1
r reduce_tab reduce $C/fiducial-eccentric.yaml $C/fiducial-eccentric-velocities.csv --seed 2 --samples 2000
r waveform waveform $C/fiducial-injection.yaml -o lines.ecsv --plot asd.png
r fisher fisher $C/fiducial-injection.yaml -o fisher.yaml
r simulate simulate $C/fiducial-injection.yaml --seed 1 --steps 60 --walkers 32 -o posterior.yaml --plots simfigs/
r horizon_post horizon posterior.yaml
r help --help
for c in plan export reduce simulate horizon validate ephemeris feasibility fisher waveform; do r help_$c $c --help; done
r bad validate /nonexistent.yaml
