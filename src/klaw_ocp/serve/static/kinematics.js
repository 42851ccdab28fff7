// The page's forward kinematics: each frame's joint and end-site positions from the pelvis centre
// and the 56 angles a step message carries, as klaw_ocp.body_motion.skeleton.forward_kinematics
// makes them on the server (the same products in the same order: they agree to about 1e-15 m).
// The skeleton message gives the body: each joint's parent (parents before children) and rest
// offset from it, each end site's carrier joint and offset, and each angle's joint, slot in the
// joint's Z, X, Y channel order (0, 1, 2) and sign (docs/serve.md, "Messages").

// base64 of little-endian float64s (numpy's '<f8' bytes) as a Float64Array; every platform a
// browser runs on is little-endian, so the bytes are read in place
export function float64s(base64) {
  const text = atob(base64), bytes = new Uint8Array(text.length);
  for (let i = 0; i < text.length; i++) bytes[i] = text.charCodeAt(i);
  return new Float64Array(bytes.buffer);
}

// root: n x 3 and angles: n x 56 numbers, frame by frame (rad, m); returns n Float64Arrays, each the
// flat [x, y, z, ...] of the joints then the end sites (m): what Scene.pose draws
export function forwardKinematics(skeleton, root, angles) {
  const { parents, offsets, end_sites: carriers, end_site_offsets: carried } = skeleton;
  const joints = parents.length, sites = carriers.length, count = skeleton.angle_joint.length;
  const frames = root.length / 3;
  if (angles.length !== frames * count) {
    throw new Error(`angles: ${angles.length} numbers for ${frames} frames of ${count}`);
  }
  // each joint's cosines and sines of its z, x, y angles (1 and 0 for the axes it has none of)
  const trig = new Float64Array(6 * joints), rotations = new Float64Array(9 * joints);
  const out = [];
  for (let f = 0; f < frames; f++) {
    for (let j = 0; j < joints; j++) {
      trig[6 * j] = trig[6 * j + 2] = trig[6 * j + 4] = 1;
      trig[6 * j + 1] = trig[6 * j + 3] = trig[6 * j + 5] = 0;
    }
    for (let a = 0; a < count; a++) {
      const value = angles[f * count + a] * skeleton.angle_sign[a];
      const k = 6 * skeleton.angle_joint[a] + 2 * skeleton.angle_slot[a];
      trig[k] = Math.cos(value); trig[k + 1] = Math.sin(value);
    }
    const points = new Float64Array(3 * (joints + sites));
    for (let j = 0; j < joints; j++) {
      // the local rotation Rz(z) Rx(x) Ry(y) (skeleton.py's _zxy_from_trig)
      const cz = trig[6 * j], sz = trig[6 * j + 1], cx = trig[6 * j + 2], sx = trig[6 * j + 3],
            cy = trig[6 * j + 4], sy = trig[6 * j + 5];
      const local = [cz * cy - sz * sx * sy, -sz * cx, cz * sy + sz * sx * cy,
                     sz * cy + cz * sx * sy, cz * cx, sz * sy - cz * sx * cy,
                     -cx * sy, sx, cx * cy];
      const p = parents[j], r = 9 * j;
      if (p < 0) {           // the root: at the frame's root position, turned by its own rotation
        rotations.set(local, r);
        points[3 * j] = root[3 * f]; points[3 * j + 1] = root[3 * f + 1]; points[3 * j + 2] = root[3 * f + 2];
        continue;
      }
      // its position: the parent's plus the parent's rotation times its offset; its rotation: the
      // parent's times its local one
      const q = 9 * p, o = offsets[j];
      for (let i = 0; i < 3; i++) {
        const a0 = rotations[q + 3 * i], a1 = rotations[q + 3 * i + 1], a2 = rotations[q + 3 * i + 2];
        points[3 * j + i] = points[3 * p + i] + (a0 * o[0] + a1 * o[1] + a2 * o[2]);
        for (let c = 0; c < 3; c++) {
          rotations[r + 3 * i + c] = a0 * local[c] + a1 * local[3 + c] + a2 * local[6 + c];
        }
      }
    }
    // the end sites: their carrier's position plus its rotation times their offset
    for (let k = 0; k < sites; k++) {
      const j = carriers[k], q = 9 * j, o = carried[k], s = 3 * (joints + k);
      for (let i = 0; i < 3; i++) {
        points[s + i] = points[3 * j + i] + (rotations[q + 3 * i] * o[0] + rotations[q + 3 * i + 1] * o[1]
                                             + rotations[q + 3 * i + 2] * o[2]);
      }
    }
    out.push(points);
  }
  return out;
}

// a step message's frames ({root, angles}: base64 as above) as each frame's points
export function framePoints(skeleton, frames) {
  return forwardKinematics(skeleton, float64s(frames.root), float64s(frames.angles));
}
