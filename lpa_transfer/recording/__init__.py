"""ROS 2 bags as MCAP files in rosbag2's layout, written and read without rclpy
(``python -m lpa_transfer.recording.bag FILE`` summarises one).
"""
