"""lpa_transfer_nodes: thin rclpy adapters around the lpa_transfer library.

Installed from nodes/ as the package ``lpa_transfer_nodes``; every module here that defines
``main()`` becomes a console script of the same name (see setup.py).
"""
