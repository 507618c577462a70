"""Thesis chapter 3, §3.6: the illustrative example. Two planar 2-link arms (Table 3.1), PA
and LPA mappings learned from N correspondences, scored by the mapping error and by the error
of the target's forward-kinematics model trained on transferred experience (Fig. 3-6), over
training sizes (experiment 1) and target link lengths (experiment 2, Fig. 3-8).
"""



