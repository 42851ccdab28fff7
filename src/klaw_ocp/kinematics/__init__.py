"""Kinematic "cosmetics" (section 4, principles 2 and 3): the 37-joint skeleton and its angles
(:mod:`.skeleton`, :mod:`.pose`) and the virtual leg with its three foot periods
(:mod:`.virtual_leg`), the swing foot (:mod:`.swing_foot`, :mod:`.swing_feet`), the lateral
weave and the upper body (:mod:`.upper_body`); :mod:`.body_motion` puts them together on a
simulated walk (angles.csv, docs/body.md, docs/upper-body.md).

This is to be the one package that reaches back into the dynamics (the pelvis giving the swing
model its hip, the virtual leg giving swing1 its toe-off posture). The physics
(:mod:`klaw_ocp.dynamics`) and the solvers know nothing of it.
"""
