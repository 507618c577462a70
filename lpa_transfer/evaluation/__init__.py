"""Reading learning curves across the chapters: time to reach a level, time saved, and the
paired and unpaired comparisons of runs over seeds.
"""
