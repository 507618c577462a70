"""Thesis chapter 6: goal babbling of inverse kinematics (Alg. 6), transfer of experience
after guided exploration, the guard against negative transfer, reaching evaluation, experiment 1
and the analysis of its reaching curves.
"""
