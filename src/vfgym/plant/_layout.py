"""Index layout of the plain arrays the compiled kernel reads and writes.

The kernel takes one float64 row of parameters per run and writes one float64 row of
streamed accumulators per run; these constants name the slots. Both the kernel and the
plain-Python reference use them, so the two read the same numbers.
"""

# --- parameter row -----------------------------------------------------------------------
P_TICK_S = 0  # T (s)
P_DELTA = 1  # pulse equivalent δ (rad)
P_VALUE = 2  # V-F threshold value (rad)
P_LIMIT = 3  # error limit L (rad)
P_STEP = 4  # value/k (rad per tick), one division done once
P_LAW = 5  # 0 = rise, 1 = slew
P_GEAR = 6  # encoder counts per command pulse (whole)
P_NS = 7  # servo sample period in ticks (whole)
P_B = 8  # speed counter multiplier
P_A = 9  # filter ratio Ts/Tf
P_K3 = 10  # N·m per count of servo error
P_COUNT_RAD = 11  # angle of one encoder count (rad)
P_INV_J = 12  # 1/J (1/(kg·m²))
P_DAMP = 13  # b/J (1/s)
P_CWW = 14  # ω(T) = CWW·ω + CWF·F
P_CWF = 15
P_CTW = 16  # θ(T) = θ + CTW·ω + CTF·F
P_CTF = 17
P_TC = 18  # Coulomb friction (N·m)
P_TLOAD = 19  # load torque (N·m)
P_TPEAK = 20  # peak torque (N·m)
P_WKNEE = 21  # end of the flat part of the torque–speed curve (rad/s)
P_WMAX = 22  # maximum speed: no motoring torque above (rad/s)
P_SLOPE = 23  # dτ/dω between knee and max speed (N·m·s/rad, ≤ 0)
P_TARGET = 24  # final command (rad): the in-position target
P_WIN_RAD = 25  # in-position half-width (rad)
P_SS_START = 26  # first tick of the steady-state window
P_ACC_W = 27  # pulse-acceleration window (ticks, whole)
P_ACC_SCALE = 28  # δ/(w·T)²: converts a second difference of counts to rad/s²
P_USE_EXT = 29  # 1: pulses come from the external source array, 0: V-F controller
N_PARAMS = 30

# --- accumulator row (streamed measures; see vfgym.plant.measures for the definitions) -----------
A_OV_MOTOR = 0  # max over at-rest ticks of dir·(θ − P) (rad), ≥ 0
A_OV_PULSE = 1  # the same for the pulse position n·δ
A_LAST_OUT_MOTOR = 2  # last tick with |θ − target| > window (−1: never)
A_LAST_OUT_PULSE = 3  # the same for n·δ
A_SS_SUM_MOTOR = 4  # Σ (θ − target) over the steady window
A_SS_SUM_PULSE = 5
A_SS_COUNT = 6
A_ACC_PULSE = 7  # max |second difference of n over w| · δ/(wT)² (rad/s²)
A_ACC_MOTOR = 8  # max |ω_{i+1} − ω_i| / T (rad/s²)
A_SAT_TICKS = 9  # ticks with the torque command clipped
A_TRK_SQ_MOTOR = 10  # Σ (P − θ)²
A_TRK_MAX_MOTOR = 11  # max |P − θ|
A_TRK_SQ_PULSE = 12  # Σ (P − nδ)²
A_TRK_MAX_PULSE = 13
A_RIPPLE_SQ = 14  # Σ over servo samples of (second difference of mean speed)²
A_RIPPLE_N = 15
A_PULSES = 16  # pulses output (either sign)
A_REVERSALS = 17  # sign changes between consecutive pulses
A_MIN_INTERVAL = 18  # shortest interval between consecutive pulses (ticks; 0: < 2 pulses)
A_FIRST_PULSE = 19  # tick of the first pulse (−1: none)
A_LAST_PULSE = 20  # tick of the last pulse (−1: none)
A_TORQUE_MAX = 21  # max |τ| (N·m)
A_PC_MAX = 22  # max |position counter| (counts)
A_THETA = 23  # final θ (rad)
A_OMEGA = 24  # final ω (rad/s)
A_N = 25  # final pulse count
A_PC = 26  # final position counter
A_SPEED_MAX = 27  # max |ω| (rad/s)
A_TICKS = 28  # ticks simulated
N_ACC = 29

# --- trace rows -----------------------------------------------------------------------------
R_COMMAND = 0  # P (rad)
R_PULSE = 1  # n·δ (rad)
R_THETA = 2  # motor angle (rad)
R_OMEGA = 3  # motor speed (rad/s)
R_TORQUE = 4  # torque applied (N·m)
R_ERROR = 5  # servo error u = pc − y (counts)
R_PC = 6  # position counter (counts)
R_FEEDBACK = 7  # filtered speed feedback y (counts)
R_SPEED_COUNT = 8  # latched speed counter output x = B·count (counts)
N_ROWS = 9

# --- loop state (one float64 row; whole numbers are exact up to 2**53) ------------------
S_N = 0  # pulses output (signed)
S_SUM = 1  # V-F accumulator
S_EPREV = 2  # limited error of the last tick
S_CPREV = 3  # encoder count the servo saw last
S_C = 4  # encoder count now
S_PC = 5  # position counter
S_SC = 6  # speed counter (counts this sample)
S_NSLEFT = 7  # ticks left in this sample period
S_Y = 8  # filtered speed feedback
S_X = 9  # latched speed counter output
S_THETA = 10  # motor angle
S_OMEGA = 11  # motor speed
S_TAU = 12  # torque applied last tick
S_U = 13  # servo error last tick
S_PPREV = 14  # command on the last tick
S_LASTDIR = 15  # sign of the command's last change
S_OVM = 16
S_OVP = 17
S_LOM = 18
S_LOP = 19
S_SSM = 20
S_SSP = 21
S_SSN = 22
S_SAT = 23
S_TSQM = 24
S_TMXM = 25
S_TSQP = 26
S_TMXP = 27
S_RIPSQ = 28
S_RIPN = 29
S_THS0 = 30
S_V1 = 31
S_V2 = 32
S_NSAMP = 33
S_PULSES = 34
S_REV = 35
S_MINIV = 36
S_FIRSTP = 37
S_LASTP = 38
S_LASTSIGN = 39
S_TQMX = 40
S_PCMX = 41
S_WMX = 42
S_D2MX = 43
S_DWMX = 44
S_TICK = 45  # next tick to simulate
N_STATE = 46
