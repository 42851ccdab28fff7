// The live strips under the body: the hip height against its sinusoid, the joint torques and the
// gait diagram, over the last few seconds, each coloured by subphase (the plots' colours,
// figures/plot_style.py; Okabe-Ito, colour-blind safe).
export const SUBPHASE_COLOURS = {
  stance: "#0072B2", double_support: "#999999", swing1: "#E69F00", swing2: "#D55E00", swing3: "#009E73",
};
const TORQUES = [["F_theta1", "#0072B2", "Fθ1 stance hip"], ["F_theta2", "#000000", "Fθ2 trunk"],
                 ["F_theta3", "#E69F00", "Fθ3 swing hip"], ["F_theta4", "#D55E00", "Fθ4 swing knee"]];
const WINDOW_S = 4.0;

export class Strips {
  constructor(hip, torque, gait, legend) {
    this.hip = hip; this.torque = torque; this.gait = gait;
    this.steps = [];
    legend.innerHTML = Object.entries(SUBPHASE_COLOURS).map(([n, c]) => `<span><i style="background:${c}"></i>${n.replace("_", " ")}</span>`).join("")
      + TORQUES.map(([, c, label]) => `<span><i style="background:${c};height:3px"></i>${label}</span>`).join("")
      + `<span><i style="background:#000;height:2px"></i>hip height</span><span><i style="background:#888;height:1px"></i>its sinusoid</span>`;
  }

  reset() { this.steps = []; }

  add(step) {
    this.steps.push(step);
    if (this.steps.length > 40) this.steps.shift();
  }

  draw(now) {
    const t0 = now - WINDOW_S;
    const visible = this.steps.filter((s) => s.t_start + s.t_step >= t0 && s.t_start <= now);
    this.drawHip(visible, t0, now);
    this.drawTorques(visible, t0, now);
    this.drawGait(visible, t0, now);
  }

  prepare(canvas) {
    const w = canvas.clientWidth;
    if (canvas.width !== w) canvas.width = w;
    const ctx = canvas.getContext("2d");
    ctx.clearRect(0, 0, canvas.width, canvas.height);
    ctx.font = "11px system-ui, sans-serif";
    return ctx;
  }

  band(ctx, visible, t0, now, y, h) {
    // the hind leg's subphases of each step, behind the curves
    const x = (t) => (t - t0) / WINDOW_S * ctx.canvas.width;
    for (const s of visible) {
      for (const [name, a, b] of s.subphases) {
        if (a > now) continue;
        ctx.fillStyle = SUBPHASE_COLOURS[name === "stance" ? "double_support" : name] + "33";
        const start = name === "stance" ? a : a;
        const end = name === "stance" ? s.t_start + s.t_ds : Math.min(b, now);
        ctx.fillRect(x(start), y, x(Math.min(end, now)) - x(start), h);
      }
    }
  }

  curve(ctx, visible, t0, now, column, colour, lo, hi, width) {
    const W = ctx.canvas.width, H = ctx.canvas.height;
    ctx.strokeStyle = colour; ctx.lineWidth = width; ctx.beginPath();
    let pen = false;
    for (const s of visible) {
      const d = s.dynamics;
      for (let i = 0; i < d.t.length; i++) {
        const v = d[column][i];
        if (d.t[i] > now || v === null) { pen = false; continue; }
        const px = (d.t[i] - t0) / WINDOW_S * W, py = H - 14 - (v - lo) / (hi - lo) * (H - 20);
        if (pen) ctx.lineTo(px, py); else ctx.moveTo(px, py);
        pen = true;
      }
    }
    ctx.stroke();
  }

  range(visible, columns) {
    let lo = Infinity, hi = -Infinity;
    for (const s of visible) for (const c of columns) for (const v of s.dynamics[c]) {
      if (v !== null) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    }
    if (!isFinite(lo)) return [0, 1];
    const pad = 0.08 * (hi - lo || 1);
    return [lo - pad, hi + pad];
  }

  drawHip(visible, t0, now) {
    const ctx = this.prepare(this.hip);
    this.band(ctx, visible, t0, now, 0, ctx.canvas.height - 14);
    const [lo, hi] = this.range(visible, ["hip_y", "hip_y_ref"]);
    this.curve(ctx, visible, t0, now, "hip_y_ref", "#888", lo, hi, 1);
    this.curve(ctx, visible, t0, now, "hip_y", "#000", lo, hi, 2);
    ctx.fillStyle = "#222";
    ctx.fillText(`hip height y (m), ${lo.toFixed(3)} – ${hi.toFixed(3)}; walk time (s) →`, 4, ctx.canvas.height - 2);
  }

  drawTorques(visible, t0, now) {
    const ctx = this.prepare(this.torque);
    this.band(ctx, visible, t0, now, 0, ctx.canvas.height - 14);
    const [lo, hi] = this.range(visible, TORQUES.map(([c]) => c));
    for (const [c, colour] of TORQUES) this.curve(ctx, visible, t0, now, c, colour, lo, hi, 1.5);
    ctx.fillStyle = "#222";
    ctx.fillText(`joint torques (N·m), ${lo.toFixed(0)} – ${hi.toFixed(0)}`, 4, ctx.canvas.height - 2);
  }

  drawGait(visible, t0, now) {
    // one row a leg: its stance (the stance leg all step, the hind leg in double support) and its swing subphases
    const ctx = this.prepare(this.gait);
    const W = ctx.canvas.width, x = (t) => (t - t0) / WINDOW_S * W;
    const rows = { right: 2, left: 18 };
    for (const s of visible) {
      const hind = s.stance_leg === "right" ? "left" : "right";
      const end = Math.min(s.t_start + s.t_step, now);
      ctx.fillStyle = SUBPHASE_COLOURS.stance;
      ctx.fillRect(x(s.t_start), rows[s.stance_leg], x(end) - x(s.t_start), 12);
      for (const [name, a, b] of s.subphases) {
        if (a > now) continue;
        const from = name === "stance" ? s.t_start : a, to = name === "stance" ? s.t_start + s.t_ds : b;
        ctx.fillStyle = SUBPHASE_COLOURS[name === "stance" ? "double_support" : name];
        ctx.fillRect(x(from), rows[hind], x(Math.min(to, now)) - x(from), 12);
      }
    }
    ctx.fillStyle = "#222";
    ctx.fillText("right", 4, 12); ctx.fillText("left", 4, 28);
    ctx.fillText("gait diagram", 4, 43);
  }
}
