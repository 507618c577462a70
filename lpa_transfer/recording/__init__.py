"""ROS 2 bags as MCAP files in rosbag2's layout, written and read without rosbag2 itself
(``python -m lpa_transfer.recording.bag FILE`` summarises one).
"""
from lpa_transfer._lazy import lazy_names

#: The public names and their modules, imported on first use (PEP 562): reading a bag imports
#: no scene rendering.
_LAZY = {
    **dict.fromkeys(["BagError", "BagWriter", "describe", "read_messages", "split_type_name",
                     "summary"], "lpa_transfer.recording.bag"),
}
__all__ = list(_LAZY)
__getattr__, __dir__ = lazy_names(__name__, _LAZY, globals())
