"""Exploration that yields correspondences: motor babbling programs (straight lines in joint
or task space), guided exploration (thesis Alg. 7), and pairing two robots' samples into
correspondence files for the transfer model.
"""
