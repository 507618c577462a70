"""Chapter 4's graph outputs (thesis §4.5): the report of mapping and encoding errors per
robot beside Table 4.3, and the letters on the robots in 3-D (like Fig. 4-11, 4-13, 4-15).
"""
import matplotlib.pyplot as plt
import numpy as np

from lpa_transfer.lfd.skills import THESIS_TABLE


THESIS = ("thesis §4.5.1-4.5.2: mapping errors on average below 0.01 m (Fig. 4-10); encoding "
          "errors comparable with the IK method's (Fig. 4-12); Table 4.3 (human -> Meka): "
          "mapping 4.5 mm, encoding 14.0 mm")


def graph_report(results, table, n_demos, teacher, learner):
    lines = [f"Thesis §4.5 over the node graph: {n_demos} demonstrations by the human, mapped "
             f"by lpa_mapping and encoded and executed by each robot's skill_learner on its "
             f"robot_sim (mm; mapping: every point, encoding: each shape's first "
             f"demonstration as executed)", "",
             f"{'robot':18s}{'pairs':>8s}{'clusters':>10s}{'mapping':>10s}{'encoding':>10s}"
             f"{'IK method':>11s}"]
    for name, r in results.items():
        lines.append(f"{name:18s}{r['pairs']:8d}{r['clusters']:10d}"
                     f"{r['mapping_error'] * 1e3:10.1f}"
                     f"{r['transferred_encoding_error'] * 1e3:10.1f}"
                     f"{r['ik_method_encoding_error'] * 1e3:11.1f}")
    lines += ["", f"Table 4.3 over the graph ({learner} taught directly or via {teacher}; "
                  f"thesis in brackets):", f"{'':12s}{'mapping':>18s}{'encoding':>18s}"]
    for condition, errors in table.items():
        (tm, _), (te, _) = THESIS_TABLE[condition]
        lines.append(f"{condition:12s}{errors['mapping_error'] * 1e3:9.1f} ({tm * 1e3:4.1f})  "
                     f"{errors['encoding_error'] * 1e3:9.1f} ({te * 1e3:4.1f})")
    return "\n".join(lines + ["", THESIS]) + "\n"


STYLES = {"demonstrated": dict(color="tab:red", lw=2.5, label="demonstration (T_R^H x_H)"),
          "mapped": dict(color="tab:green", lw=1.2, label="transferred (FK of LPA joints)"),
          "transferred": dict(color="tab:blue", lw=1.2, ls="--",
                              label="DMP of transferred, executed"),
          "ik_method": dict(color="black", lw=0.8, ls=":", label="DMP of own IK, executed"),
          "refined": dict(color="tab:orange", lw=1.2, ls="-.",
                          label="via the teacher, refined: DMP executed"),
          "unrefined": dict(color="tab:purple", lw=1.2, ls=":",
                            label="via the teacher, unrefined: DMP executed")}


def plot_letters(path, traces):
    """Fig. 4-11/4-13 like: per robot, every shape's first demonstration in the robot's frame
    with its transferred and executed reproductions, in 3-D; Fig. 4-15 like: the learner's
    executed letters taught directly and via the teacher."""
    fig = plt.figure(figsize=(6.5 * len(traces), 6.0))
    for col, (name, trace) in enumerate(traces.items(), start=1):
        ax = fig.add_subplot(1, len(traces), col, projection="3d")
        extent = np.ptp(np.vstack([p for t in trace.values() for p in t.values()]), axis=0)
        ax.set_box_aspect(extent[[0, 2, 1]] + 1e-3)       # metres look like metres
        for key, style in STYLES.items():
            for k, points in enumerate(trace.get(key, {}).values()):
                ax.plot(points[:, 0], points[:, 2], points[:, 1],
                        **{**style, "label": style["label"] if k == 0 else None})
        ax.set_xlabel("x forward (m)")
        ax.set_ylabel("z right (m)")
        ax.set_zlabel("y up (m)")
        ax.set_title(name)
        ax.legend(fontsize=7, loc="upper left")
    fig.suptitle("Letters on the robots (like thesis Fig. 4-11, 4-13 and 4-15)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
