#!/usr/bin/env bash
# The pictures of docs/gallery.md: runs every bundled case into out/gallery/<case> (a run
# that finished or came to rest there is reused) and draws it with `loam plot` into
# docs/img/gallery/. About 20 minutes on 2 cores for the runs (collapse_bui2008_tri_h2
# alone 10 min), seconds for the pictures.
#   cargo build --release && scripts/gallery.sh
set -euo pipefail
cd "$(dirname "$0")/.."
LOAM=${LOAM:-target/release/loam}
OUT=out/gallery
IMG=docs/img/gallery
BUI=tests/data/bui2008
mkdir -p "$IMG"

run() {
  if ! grep -qs '"status": "\(finished\|at_rest\)"' "$OUT/$1/summary.json"; then
    nice "$LOAM" run "cases/$1.json" --out "$OUT/$1" --quiet
  fi
}

# frames NAME CASE [loam plot options]: the frames drawn, as NAME.png (one frame) or
# NAME_<k>.png (k = 1, 2, … in time order)
frames() {
  local name=$1 case=$2 tmp
  shift 2
  run "$case"
  tmp=$(mktemp -d)
  "$LOAM" plot "$OUT/$case" --out "$tmp" --no-monitors "$@" > /dev/null
  mapfile -t files < <(ls "$tmp"/*.png | sort)
  if [ "${#files[@]}" = 1 ]; then
    cp "${files[0]}" "$IMG/$name.png"
  else
    for k in "${!files[@]}"; do cp "${files[$k]}" "$IMG/${name}_$((k + 1)).png"; done
  fi
  rm -r "$tmp"
}

# monitors NAME CASE FILE [loam plot options]: the monitor plot FILE as NAME.png
monitors() {
  local name=$1 case=$2 file=$3 tmp
  shift 3
  run "$case"
  tmp=$(mktemp -d)
  "$LOAM" plot "$OUT/$case" --out "$tmp" --no-frames "$@" > /dev/null
  cp "$tmp/$file" "$IMG/$name.png"
  rm -r "$tmp"
}

KAPPA=accumulated_plastic_deviatoric_strain

# benchmark 1: cantilever
frames cantilever_fem cantilever_fem --field von_mises_stress --last
frames cantilever_fem_dynamic cantilever_fem_dynamic --field displacement:y --times 0.5
monitors cantilever_fem_dynamic_tip cantilever_fem_dynamic monitors_length.png --monitors tip_uy
monitors cantilever_fmu cantilever_fmu monitors_length.png --monitors tip_uy
frames cantilever_mpm cantilever_mpm --field displacement:y --last
frames cantilever_mpm_point_load cantilever_mpm_point_load --field displacement:y --last
frames cantilever_mpm_dynamic cantilever_mpm_dynamic --field displacement:y --times 0.5
# benchmark 2: axisymmetric plate; 3: vibrating bar; 4: disks; 5: hydrostatic column
frames plate_axisym_mpm plate_axisym_mpm --field displacement:y --last
frames vibrating_bar_mpm vibrating_bar_mpm --field velocity:x --times 0
monitors vibrating_bar_mpm_energy vibrating_bar_mpm monitors_energy.png
frames disk_collision_mpm disk_collision_mpm --field velocity --times 1,1.9,2.8 --range 0,0.15
monitors disk_collision_mpm_energy disk_collision_mpm monitors_energy.png
frames hydrostatic_column_mpm hydrostatic_column_mpm --field cauchy_stress:yy --last --grid
# benchmarks 6 and 7: penalty walls and slip boundaries
frames cylinder_incline_slip_mpm cylinder_incline_slip_mpm --field velocity --last
frames cylinder_incline_noslip_mpm cylinder_incline_noslip_mpm --field velocity --last
frames slip_flat_mpm slip_flat_mpm --field cauchy_stress:yy --last
frames slip_slope_mpm slip_slope_mpm --field velocity --last
frames block_friction_grid_mpm block_friction_grid_mpm --field velocity --last
frames rigid_disk_rolling_on_mpm rigid_disk_rolling_on_mpm --field velocity --times 0.2,0.4 --range 0,1.1
# benchmark 8: Bui et al. 2008 collapse, with the experiment's surface and failure line
for c in collapse_bui2008_quad_mc collapse_bui2008_quad_rough collapse_bui2008_quad_mc_h10 collapse_bui2008_quad_mc_h2.5 collapse_bui2008_tri collapse_bui2008_tri_h2 \
  collapse_bui2008_mu_i collapse_bui2008_quad; do
  frames "$c" "$c" --field $KAPPA --last --range 0,2 --max-stretch 2 \
    --overlay "$BUI/surface.csv:experiment, surface" --overlay "$BUI/failure.csv:experiment, failure line"
done
monitors collapse_bui2008_quad_mc_runout collapse_bui2008_quad_mc monitors_length.png
frames collapse_bui2008_slab_3d collapse_bui2008_slab_3d --field $KAPPA --last --range 0,2 --max-stretch 2 --plane xz \
  --overlay "$BUI/surface.csv:experiment, surface" --overlay "$BUI/failure.csv:experiment, failure line"
frames collapse_two_layers collapse_two_layers --field $KAPPA --last --range 0,2 --max-stretch 2
# benchmark 9: cohesive soil
frames collapse_cohesive collapse_cohesive --field $KAPPA --times 0.6,0.88,1.28,2.0 --range 0,1
frames vertical_cut_1m vertical_cut_1m --field $KAPPA --last
frames vertical_cut_3m vertical_cut_3m --field $KAPPA --last --range 0,1
# granular flows: repose, discharge
for c in repose_phi20 repose_phi35; do frames "$c" "$c" --field $KAPPA --last --range 0,2 --max-stretch 2; done
for c in discharge_d08 discharge_d12 discharge_d12_coarse discharge_d18; do frames "$c" "$c" --field velocity --times 0.15; done
# localisation: biaxial compression, FEM and MPM
for c in biaxial_mc_softening biaxial_mcc biaxial_mc_softening_mpm biaxial_mcc_mpm; do frames "$c" "$c" --field $KAPPA --last; done
monitors biaxial_mc_softening_force biaxial_mc_softening monitors_force_vs_top_uy.png --x top_uy --monitors top_force
monitors footing_fmu footing_fmu monitors_force_vs_footing_uy.png --x footing_uy --monitors footing_force
# soil-structure interaction: MPM soil and FEM structures in one Newton system
frames coupled_beam_split coupled_beam_split --field displacement:y --last
frames coupled_beam_split_3d coupled_beam_split_3d --field displacement:y --last
frames coupled_beam_split_mpm_clamped coupled_beam_split_mpm_clamped --field displacement:y --last
frames coupled_beam_split_dynamic coupled_beam_split_dynamic --field displacement:y --times 0.65
for c in coupled_collapse_rubber coupled_collapse_concrete; do
  frames "$c" "$c" --field $KAPPA --times 0.15,0.55 --range 0,2 --max-stretch 2
  monitors "${c}_force" "$c" monitors_force.png
done
monitors coupled_wave_bar coupled_wave_bar monitors_energy.png
monitors coupled_wave_bar_impedance coupled_wave_bar_impedance monitors_energy.png
frames coupled_slip_block coupled_slip_block --field velocity:x --last
# mixed u–p formulation (issue 15)
frames cooks_membrane_up cooks_membrane_up --field pressure --last
frames thick_cylinder_up thick_cylinder_up --field pressure --last
frames hydrostatic_column_mpm_up hydrostatic_column_mpm_up --field pressure --last --grid
for c in footing_undrained_mpm_up footing_undrained_mpm_u coupled_footing_rough_up; do
  frames "$c" "$c" --field von_mises_stress --last
  monitors "${c}_curve" "$c" monitors_q_over_su_vs_settlement.png --x settlement --monitors q_over_su
done
frames footing_undrained_fem_up footing_undrained_fem_up --field von_mises_stress --last
monitors footing_undrained_fem_up_curve footing_undrained_fem_up monitors_q_over_su_vs_settlement.png --x settlement --monitors q_over_su
frames collapse_bui2008_quad_up collapse_bui2008_quad_up --field $KAPPA --last --range 0,2 --max-stretch 2 \
  --overlay "$BUI/surface.csv:experiment, surface" --overlay "$BUI/failure.csv:experiment, failure line"
echo "gallery: $(ls "$IMG" | wc -l) pictures in $IMG ($(du -sh "$IMG" | cut -f1))"
