"""ROS 2 bags as MCAP files in rosbag2's layout, written and read without rosbag2 itself
(``python -m lpa_transfer.recording.bag FILE`` summarises one).
"""
