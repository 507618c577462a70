"""Exploration that yields correspondences: motor babbling programs (straight lines in joint
or task space), guided exploration (thesis Alg. 7), and pairing two robots' samples into
correspondence files for the transfer model.
"""
from lpa_transfer._lazy import lazy_names

#: The public names and their modules, imported on first use (PEP 562): a babbling node
#: imports no correspondence pairing.
_LAZY = {
    **dict.fromkeys(["PROGRAMS", "BabblingProgram", "box_around"],
                    "lpa_transfer.exploration.babbling"),
    **dict.fromkeys(["BAD_PAIR_ACTIONS", "DEFAULT_FEATURES", "FEATURES", "PAIRING_RULES",
                     "check_features", "check_guided_exploration", "check_pairing_rule",
                     "collect_correspondences", "collect_guided_correspondences",
                     "load_correspondences", "load_guided_exploration", "pair_check_line",
                     "PairCheck", "read_correspondences", "run_commands", "SettlingStep"],
                    "lpa_transfer.exploration.correspondences"),
    **dict.fromkeys(["SOURCE_FOLLOWS", "TARGET_RANGES", "guided_exploration", "shared_limits"],
                    "lpa_transfer.exploration.guided"),
}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_names(__name__, _LAZY, globals())
