"""Kinematic "cosmetics" (section 4, principles 2 and 3): the virtual leg and its foot periods, the
determinants of gait (pelvis), the upper body and the 37-joint skeleton.

This is the one package that reaches back into the dynamics: the pelvis gives the swing model
its hip (:mod:`.pelvis`), and the virtual leg gives swing1 its toe-off posture. The physics
(:mod:`klaw_ocp.dynamics`) and the solvers know nothing of it.
"""
