"""The Menagerie's models and the markdown table of :mod:`benchmarks.mjcf_agreement`."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

MENAGERIE_MODELS = (
    "franka_emika_panda/panda.xml",
    "franka_fr3/fr3.xml",
    "universal_robots_ur5e/ur5e.xml",
    "universal_robots_ur10e/ur10e.xml",
    "kinova_gen3/gen3.xml",
    "kuka_iiwa_14/iiwa14.xml",
    "ufactory_xarm7/xarm7.xml",
    "ufactory_lite6/lite6.xml",
    "rethink_robotics_sawyer/sawyer.xml",
    "unitree_z1/z1.xml",
    "trossen_vx300s/vx300s.xml",
    "flexiv_rizon4/flexiv_rizon4.xml",
    "unitree_h1/h1.xml",
    "unitree_g1/g1.xml",
    "pal_talos/talos.xml",
    "robotis_op3/op3.xml",
    "booster_t1/t1.xml",
    "apptronik_apollo/apptronik_apollo.xml",
    "stanford_tidybot/tidybot.xml",
    "hello_robot_stretch/stretch.xml",
    "hello_robot_stretch_3/stretch.xml",
    "pal_tiago/tiago.xml",
    "unitree_go2/go2.xml",
    "unitree_go1/go1.xml",
    "unitree_a1/a1.xml",
    "anybotics_anymal_c/anymal_c.xml",
    "boston_dynamics_spot/spot.xml",
    "agility_cassie/cassie.xml",
    "agilex_piper/piper.xml",
    "aloha/aloha.xml",
    "arx_l5/arx_l5.xml",
    "franka_fr3_v2/fr3v2.xml",
    "i2rt_yam/yam.xml",
    "low_cost_robot_arm/low_cost_robot_arm.xml",
    "robotstudio_so101/so101.xml",
    "trs_so_arm100/so_arm100.xml",
    "trossen_wx250s/wx250s.xml",
    "trossen_wxai/trossen_ai_bimanual.xml",
    "dynamixel_2r/dynamixel_2r.xml",
    "google_robot/robot.xml",
    "pal_tiago_dual/tiago_dual.xml",
    "berkeley_humanoid/berkeley_humanoid.xml",
    "fourier_n1/n1.xml",
    "pndbotics_adam_lite/adam_lite.xml",
    "toddlerbot_2xc/toddlerbot_2xc.xml",
    "toddlerbot_2xm/toddlerbot_2xm.xml",
    "anybotics_anymal_b/anymal_b.xml",
    "google_barkour_vb/barkour_vb.xml",
    "shadow_hand/right_hand.xml",
    "leap_hand/right_hand.xml",
    "wonik_allegro/right_hand.xml",
    "robotiq_2f85/2f85.xml",
    "shadow_dexee/shadow_dexee.xml",
)
"""Menagerie models run by ``--menagerie`` (arms, humanoids, mobile and legged robots)."""

TABLE_HEADER = (
    "| model | MuJoCo loads | clik loads (or its error) | FK max m / rad "
    "| geoms compared | geom placement max m | probe distance max m |"
)


def _number(value: float | None) -> str:
    """A measure for the table (``-`` when not taken)."""
    return "-" if value is None else f"{value:.2g}"


def table(results: Sequence[dict[str, Any]], root: Path | None = None) -> str:
    """The results as a markdown table (one row per model)."""
    lines = [TABLE_HEADER, "|" + " --- |" * 7]
    for r in results:
        name = r["model"]
        if root is not None and Path(name).is_relative_to(root):
            name = str(Path(name).relative_to(root))
        mujoco = "yes" if r["mujoco"] == "ok" else r["mujoco"].replace("|", "/")
        clik = r["clik"].replace(f"cannot load robot {r['model']}, ", "").replace("|", "/")
        if r["clik"] == "ok":
            clik = f"yes ({r['base']})"
        fk = (
            "-"
            if r["fk_position_m"] is None
            else f"{_number(r['fk_position_m'])} / {_number(r['fk_rotation_rad'])}"
        )
        lines.append(
            f"| {name} | {mujoco} | {clik} | {fk} | {r['geoms_compared']} "
            f"| {_number(r['geom_placement_m'])} | {_number(r['probe_distance_m'])} |"
        )
    notes = [(r["model"], n) for r in results for n in r["notes"]]
    if notes:
        lines += ["", "Notes:", ""]
        for model, note in notes:
            shown = (
                Path(model).relative_to(root)
                if root and Path(model).is_relative_to(root)
                else model
            )
            lines.append(f"- {shown}: {note.replace('|', '/')}")
    return "\n".join(lines) + "\n"
