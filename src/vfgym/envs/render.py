"""The environments' ``rgb_array`` picture: position, speed and acceleration of a move, the
command against the motor. Matplotlib (Agg, no window) is imported only here, on demand."""

from __future__ import annotations

import numpy as np

from vfgym.params import Plant

WIDTH_PX = 640
HEIGHT_PX = 480
MAX_POINTS = 2000
SPEED_WINDOW_S = 2e-4


def _window_diff(x: np.ndarray, w: int) -> np.ndarray:
    """x_i − x_(i−w), with x = 0 before the start (the plant starts at rest at 0)."""
    padded = np.concatenate([np.zeros(w), x])
    return padded[w:] - padded[:-w]


def move_picture(
    plant: Plant,
    command_rad: np.ndarray,
    pulse_rad: np.ndarray | None,
    motor_rad: np.ndarray | None,
    speed_rad_s: np.ndarray | None,
    accel_window_s: float,
    title: str,
) -> np.ndarray:
    """An (H, W, 3) uint8 picture of one move sampled every tick.

    Position: the command P, the V-F controller's pulse position n·δ (what the servo is
    commanded) and the motor angle θ. Speed: the pulse train's speed over 0.2 ms and the
    motor's. Acceleration: the pulse counts' over the measure's window w (within their
    quantum 2δ/w² of the measure, which reads the train's unquantised position,
    docs/model.md §5.1) and the motor's over the same window, with the motor's limit.
    Without a
    simulated move (``motor_rad`` None) only the command is drawn.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    f = plant.tick_hz
    n = command_rad.size
    step = max(1, n // MAX_POINTS)
    t_ms = np.arange(1, n + 1)[::step] / f * 1e3
    fig = Figure(figsize=(WIDTH_PX / 100, HEIGHT_PX / 100), dpi=100)
    FigureCanvasAgg(fig)
    ax_p, ax_v, ax_a = fig.subplots(3, 1, sharex=True)
    ax_p.plot(t_ms, command_rad[::step], color="0.5", lw=1.0, ls="--", label="command P")
    limit = plant.motor.usable_accel_rad_s2
    if motor_rad is not None and pulse_rad is not None and speed_rad_s is not None:
        ws = max(1, round(SPEED_WINDOW_S * f))
        wa = max(1, round(accel_window_s * f))
        v_pulse = _window_diff(pulse_rad, ws) * f / ws
        a_pulse = _window_diff(_window_diff(pulse_rad, wa), wa) * (f / wa) ** 2
        a_motor = _window_diff(speed_rad_s, wa) * f / wa
        ax_p.plot(t_ms, pulse_rad[::step], color="tab:blue", lw=1.0, label="pulses n·δ")
        ax_p.plot(t_ms, motor_rad[::step], color="tab:red", lw=1.0, label="motor θ")
        ax_v.plot(t_ms, v_pulse[::step], color="tab:blue", lw=1.0, label="pulses")
        ax_v.plot(t_ms, speed_rad_s[::step], color="tab:red", lw=1.0, label="motor")
        ax_a.plot(t_ms, a_pulse[::step] / 1e3, color="tab:blue", lw=1.0, label="pulses")
        ax_a.plot(t_ms, a_motor[::step] / 1e3, color="tab:red", lw=1.0, label="motor")
        for s in (1, -1):
            ax_a.axhline(s * limit / 1e3, color="k", lw=0.8, ls=":")
        ax_v.legend(loc="upper right", fontsize=7)
    else:
        ax_v.text(0.5, 0.5, "not simulated yet", ha="center", va="center", transform=ax_v.transAxes)
    ax_p.legend(loc="lower right", fontsize=7)
    ax_p.set_ylabel("rad")
    ax_v.set_ylabel("rad/s")
    ax_a.set_ylabel("krad/s²")
    ax_a.set_xlabel("time (ms)")
    ax_p.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.canvas.draw()
    rgba = np.asarray(fig.canvas.buffer_rgba())
    return np.ascontiguousarray(rgba[..., :3], dtype=np.uint8)


def replay(
    w0: np.ndarray, ring_len: int, cmd: np.ndarray, actions: list[np.ndarray], ends: list[int]
) -> np.ndarray:
    """Every tick of a VFServo-v0 episode so far, simulated again from its start (the
    workspace row ``w0`` as its reset left it) with the same settings interval by interval
    (the kernel is deterministic), as trace rows: ``actions[j]`` in force up to tick
    ``ends[j]``."""
    from vfgym.plant import _kernel as K
    from vfgym.plant import _layout as L

    from . import _batch as B

    w = w0.copy()
    ring = np.zeros(ring_len)
    B.reset_row(w, ring, cmd)
    prm = w[B.W_PRM : B.W_PRM + L.N_PARAMS]
    st = w[B.W_ST : B.W_ST + L.N_STATE]
    ext = np.zeros(0, dtype=np.int8)
    parts = []
    i0 = 0
    for act, i1 in zip(actions, ends, strict=True):
        B.apply_action(act, w)
        part = np.empty((L.N_ROWS, i1 - i0), dtype=np.float64)
        K.run_segment(cmd, ext, prm, st, ring, i1, part, 1)
        parts.append(part)
        i0 = i1
    if not parts:
        return np.zeros((L.N_ROWS, 0))
    return np.concatenate(parts, axis=1)
