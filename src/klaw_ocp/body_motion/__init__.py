"""The human body on a simulated walk (section 4, principles 2 and 3; docs/body.md): the 37-joint
skeleton's root and 56 angles at every frame, rebuilt after the walk from its solved steps. It
only reads the walk (:class:`klaw_ocp.walk.Walk`): nothing here feeds back into the solving, and
the walk never imports it.

- :mod:`.motion`: :func:`body_motion`, the entry point (angles.csv's rows, :data:`ANGLES_COLUMNS`);
- :mod:`.skeleton`: the 37 joints, their rest offsets, the 56 angles (:data:`ANGLE_NAMES`) and
  the forward kinematics; :mod:`.pose`: its inverse, the angles from world points;
- :mod:`.stance_legs`: the virtual legs of every stance (:mod:`klaw_ocp.kinematics.virtual_leg`)
  evaluated together; :mod:`.swing_legs`: the swing legs hung from their own hips;
- :mod:`.swing_foot_guard`: the swing foot the body shows, kept out of the ground (every step's in
  one pass; the summary's swing-foot clearance reads it too);
- :mod:`.upper_body`: the lateral weave and the upper body following the legs;
- :mod:`.walk_samples`: the solved states between their nodes, at the body's frames;
- compiled as the solvers' kernels are (:mod:`klaw_ocp.kernels`; :func:`prepare_kernels` compiles
  or loads them ahead of the first frames): :mod:`.leg_angles` (the legs' angles from their
  points), :mod:`.stance_kernel` (the virtual legs' pitch rules and legs), :mod:`.swing_kernel`
  (the swing legs on either side of the ground guard), their shared forms :mod:`.kernel_forms`.

It builds on the leg rules the walk solved with (:mod:`klaw_ocp.kinematics`) and on the models'
points (:mod:`klaw_ocp.dynamics.points`).
"""
from .motion import ANGLES_COLUMNS, BodyMotion, body_motion, prepare_kernels
from .skeleton import ANGLE_NAMES, JOINTS, SIDES

__all__ = ["ANGLES_COLUMNS", "ANGLE_NAMES", "JOINTS", "SIDES", "BodyMotion", "body_motion", "prepare_kernels"]
