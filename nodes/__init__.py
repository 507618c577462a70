"""lpa_transfer_nodes: thin rclpy adapters around the lpa_transfer library.

Installed from nodes/ as the package ``lpa_transfer_nodes``; every module here that defines
``main()`` is a node and becomes a console script of the same name (see setup.py). The other
modules are the ROS layer the nodes share, public for your own nodes too: ``params``
(parameters declared from tables, with descriptors), ``qos`` (the topics' profiles),
``conversions`` (Matrix messages, stamps, states), ``calls`` (waiting for and calling services
and actions), ``servers`` (service callbacks and long jobs as actions), ``robot_clients`` (a
robot_sim's step and reset), ``entry`` (a node's main: spin until SIGINT/SIGTERM, shut down),
``markers`` (task markers) and ``mapping_client`` (the mapping service's client).
"""
