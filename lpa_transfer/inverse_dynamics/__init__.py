"""Thesis chapter 5: online inverse-dynamics learning of star tracking tasks, with and
without transferred experience: the tasks, the feed-forward learner and the analysis of its
learning curves (trials to convergence, training time saved).
"""
