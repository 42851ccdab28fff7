"""The leg rules the walk calls while it solves (section 4, principle 2): the kinematic parts of
each step that the dynamics and the solvers are handed.

- :mod:`.virtual_leg`: the virtual leg (§4.2) with its three foot periods, a human leg on the
  telescopic stance leg; the stance leg's rules (:class:`.virtual_leg.StanceFoot`) carried through
  the next step's double support give swing1 its toe-off posture;
- :mod:`.pitch_rules`: the foot's pitch through one stance; :mod:`.landing`: the knee and foot at
  heel strike; :mod:`.heel_up_roots`: the heel-up pitches in closed form;
- :mod:`.leg_geometry`: the leg's two-link geometry and the flat foot;
- :mod:`.swing_foot`: the swing foot's angle schedule (§4.3), the one the swing2 and swing3
  clearance paths constrain.

The body rebuilt after the walk (the 37-joint skeleton, the swing foot's ground guard, the upper
body) is :mod:`klaw_ocp.body_motion`, which builds on these and which this package never imports.
The physics (:mod:`klaw_ocp.dynamics`) and the solvers know nothing of either.
"""
