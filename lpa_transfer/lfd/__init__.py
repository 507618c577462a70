"""Thesis chapter 4: learning from demonstration with transfer. A demonstrator's letters
(LASA), demonstrator-robot correspondences, joint-space DMPs and the chapter's experiments.
"""
