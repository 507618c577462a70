"""Reading learning curves across the chapters: time to reach a level, time saved, and the
paired and unpaired comparisons of runs over seeds.
"""
from lpa_transfer._lazy import lazy_names

#: The public names and their modules, imported on first use (PEP 562), like every
#: subpackage's, so that importing the package stays cheap.
_LAZY = {
    **dict.fromkeys(["paired_comparison", "rank_sum_comparison", "time_saved", "time_to_reach"],
                    "lpa_transfer.evaluation.learning_curves"),
}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_names(__name__, _LAZY, globals())
