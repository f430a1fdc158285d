"""One place for numerical settings: numba flags, tolerances and safety factors.

Kernels import their decorator options from here, so the choice of ``fastmath`` or caching is
made once. ``fastmath`` stays off: the point-mass events are roots found to near machine
precision, and reassociation would make results depend on the compiler's mood.
"""

import os

#: Options for every ``numba.njit`` in the package. ``cache=True`` writes compiled code next to
#: the sources (``__pycache__``) so a second run does not recompile. ``error_model="numpy"``:
#: a division by zero gives IEEE's inf or nan instead of raising ZeroDivisionError, so numba
#: compiles no zero test and exception path beside every division (the kernels divide only by
#: what they know is nonzero, and the runs' instability checks catch any inf or nan); every
#: other division gives the same bits.
NUMBA_OPTIONS = {"cache": True, "fastmath": False, "nogil": True, "error_model": "numpy"}

#: Options for kernels that run a ``prange`` loop.
NUMBA_PARALLEL_OPTIONS = {**NUMBA_OPTIONS, "parallel": True}

#: Standard gravity, m/s^2 (README, Symbols).
GRAVITY = 9.81

# --- point-mass model -------------------------------------------------------------------------
#: Relative tolerance on the Poincare section state (u, w, z) for calling an orbit periodic.
PM_PERIODIC_TOL = 1e-9
#: Longest period of an orbit that is searched for, in drive cycles.
PM_MAX_ORBIT_PERIOD = 64
#: Cycles integrated before an orbit that has not closed is declared non-periodic.
PM_MAX_CYCLES = 3000
#: Cycles averaged for the mean velocity of a non-periodic motion.
PM_AVERAGE_CYCLES = 1000
#: Starting phases used to report the spread of a non-periodic motion.
PM_SPREAD_STARTS = 8
#: A bounce slower than this (normal velocity in units of A omega sin phi) ends the bouncing:
#: the remaining bounces of the geometric series are shorter than about 1e-8 of a cycle.
PM_BOUNCE_SETTLE = 1e-9
#: Hard limit on phase changes within one cycle; more means a bug or a pathological input.
PM_MAX_EVENTS_PER_CYCLE = 100_000


def default_threads() -> int:
    """Threads for numba parallel loops: NUMBA_NUM_THREADS if set, else all cores."""
    value = os.environ.get("NUMBA_NUM_THREADS")
    return int(value) if value else (os.cpu_count() or 1)


# --- DEM engine -------------------------------------------------------------------------------
#: Automatic time step, linear contact: this fraction of the collision time
#: pi / sqrt(k_n / m* - (gamma_n / 2 m*)^2) of the lightest pair (undamped time if over-damped).
DEM_DT_COLLISION_FRACTION = 1.0 / 50.0
#: Automatic time step, Hertz contact: this fraction of the Rayleigh time
#: pi R sqrt(rho / G) / (0.1631 nu + 0.8766) ...
DEM_DT_RAYLEIGH_FRACTION = 0.1
#: ... and this fraction of the Hertz collision time 2.87 (m*^2 / (R* Y*^2 v))^(1/5) at the
#: largest expected impact velocity v = A omega + sqrt(2 g h_fill).
DEM_DT_HERTZ_FRACTION = 1.0 / 50.0
#: A user time step is refused above this fraction of the critical time step 2 / omega_0 of the
#: stiffest single contact (omega_0 = sqrt(k / m*)); the margin covers grains with several
#: contacts (the stiffness seen by one grain adds up) and the damping.
DEM_DT_STABILITY_FRACTION = 0.3
#: Safety margin on a clump's sampled smallest contact mass
# (dem.scene.shapes.Template.contact_mass):
#: the time step is set as if the mass were this fraction smaller.
DEM_CONTACT_MASS_MARGIN = 0.05
#: Verlet skin as a fraction of the largest sphere radius; the list is rebuilt when a sphere has
#: moved more than half the skin since the last build.
DEM_SKIN_FRACTION = 0.25
#: Default tangential damping ratio zeta_t of ``[contact] tangential = "coulomb"``
#: (dem.physics.tangential): damps the ringing of a resting contact within a few periods.
DEM_TANGENTIAL_DAMPING_RATIO = 0.3
#: ``[contact] tangential = "impact"``: the enduring contact's stick is a spring-dashpot sized by
#: the time step, not by the material: angular frequency DEM_STICK_RATE / dt on the contact's
#: tangential mass, damping ratio DEM_STICK_DAMPING_RATIO (dem.kernels.contact). Chosen by
#: measurement (validation/impact-law, ``run.py stick``): against the point mass on a floor as
#: compliant as the contact, one sphere on 24 sliding drives at E = 5e7 Pa is within 0.91 %
#: (worst) at (0.5, 0.5), against 2.9 % at the earlier (0.2, 0.7), whose softer stick let the
#: grain slip where it should stick. Stiffer is not better: at 0.8 and above, a bed of screws at
#: rest on a floor tilted below the friction angle no longer comes to rest (its grains share
#: several sticking contacts, whose stiffnesses add past the explicit step's limit, about 1.24
#: rad a step for one contact at zeta 0.5) and creeps downhill at up to 5e-4 m/s, bounded only
#: by the Coulomb cap; at (0.5, 0.5) it rests to 1e-14 m/s, as at 0.2.
DEM_STICK_RATE = 0.5
DEM_STICK_DAMPING_RATIO = 0.5
#: ``"impact"`` with eps_n = 0: the plastic contact's normal stick (its rigid unloading,
#: dem.kernels.contact.plastic_normal), angular frequency DEM_NORMAL_STICK_RATE / dt on the
#: contact's normal mass, damping ratio DEM_STICK_DAMPING_RATIO. Chosen by the same bed as the
#: tangential stick (validation/hopping-bias, ``run.py stick``): 40 screws at rest on a floor
#: tilted to 0.9 of the friction angle, whose contacts now carry both sticks, rest to 4e-20 m/s
#: (rms) at 0.25 and 5e-16 at 0.35, and chatter at 2e-3 m/s at 0.5 (200 screws: 7e-20, 5e-20,
#: 2e-9); the lone grain's v_norm moves by less than 1e-6 between 0.25 and 0.5.
DEM_NORMAL_STICK_RATE = 0.25
#: Driven cycles before measuring in an exported deck of a case whose ``run.settle_cycles`` is
#: "auto" and no earlier dem run reports the detected number: the shipped bulk cases' detected
#: transients were 6-12 cycles (their summary.json), so 20 covers them with margin.
DEM_EXPORT_SETTLE_CYCLES = 20
#: Neighbour lists are regrown to this factor times the needed size when they overflow.
DEM_GROWTH_FACTOR = 1.5
#: Instability checks run every this many steps.
DEM_CHECK_INTERVAL = 500
#: A run that can be stopped (SIGINT/SIGTERM) checks at least this often, s: chunks shorten
#: when 500 steps take longer (large scenes).
DEM_STOP_LATENCY_S = 0.5
#: Overlap guard (dem.engine.simulation.Simulation.check), as fractions of the smaller radius,
#: sampled at every check (every DEM_CHECK_INTERVAL steps). Accuracy bound: a run whose largest
#: overlap exceeds it finishes, with a warning and the record (max_overlap_fraction: where, when,
#: the stiffness that would bring it under) in summary.json. An overlap is set by the stiffness
#: against the load and the impacts, not by the time step: a stable screw bed at LIGGGHTS parity (E
#: 5e7 Pa, Gamma 2.5) peaks at 0.107 radii for one seed of three, and LIGGGHTS finishes it.
DEM_OVERLAP_WARN_FRACTION = 0.1
#: Hard bound: an overlap beyond it stops the run. At half a radius the contact laws (small
#: strains) say nothing and a grain is half way through its neighbour or the wall; five times
#: the accuracy bound, so a stable run's impacts (0.1-0.2 radii at the softest shipped contacts)
#: stay clear of it while a soft contact that lets grains through is stopped at once.
DEM_MAX_OVERLAP_FRACTION = 0.5
#: ... and an overlap that grows without bound stops the run before it reaches that: the same
#: contact the deepest, above the accuracy bound, at this many checks in a row after the first,
#: each deeper than the last by at least this factor (0.11 -> 0.37 radii over 1500 steps). An
#: impact lasts about 50 steps (the automatic step is t_c / 50), so a check 500 steps later sees
#: another; only a contact being driven ever deeper (an integration out of its stable range)
#: grows like this.
DEM_OVERLAP_GROWTH_CHECKS = 3
DEM_OVERLAP_GROWTH_FACTOR = 1.5
#: A grain whose speed exceeds this factor times the largest speed the drive and gravity can
#: give (A omega + sqrt(2 g h_fill)) stops the run (energy the step loop made), as does a grain
#: higher above the fill than that speed throws it (a grain that outran the check between two
#: checks). A bed whose mean x-velocity is over half that speed, downhill on an inclined trough,
#: is named as running away down it.
DEM_MAX_SPEED_FACTOR = 20.0
#: Settling ends when the rms grain speed falls below this fraction of sqrt(g r).
DEM_SETTLE_SPEED_FRACTION = 0.01
#: Settling gives up after this many seconds of simulated time.
DEM_SETTLE_MAX_TIME = 5.0
#: Simulation.settle: a fill whose rms speed, after DEM_SETTLE_STEADY_AFTER s, has stayed within
#: the relative spread DEM_SETTLE_STEADY_SPREAD over the last DEM_SETTLE_STEADY_WINDOW s, below
#: DEM_SETTLE_STEADY_FACTOR times the rest threshold, is settled: grains rolling on the floor of
#: a sparse bed, which nothing stops (measured: 20 screws of screw-trough, one rolling at 8 mm/s,
#: rms 0.0018 m/s against the threshold 0.0014 for 2.8 s; 12 screws never reached rest in 5 s).
#: Late and strict, so that a bed still coming to rest is left to do so (the seeded 20-sphere
#: bed of tests/regression rests at 1.21 s; after 1 s and within 5 % it was cut at 1.0 s).
DEM_SETTLE_STEADY_AFTER = 2.0
DEM_SETTLE_STEADY_WINDOW = 0.5
DEM_SETTLE_STEADY_SPREAD = 0.02
DEM_SETTLE_STEADY_FACTOR = 10.0
#: numba's cache folders of other kernel sources (dem.kernels: one per source digest) unused for
#: this long are removed when dem.kernels is imported, s.
DEM_CACHE_KEEP_S = 7 * 86400.0
#: Random sequential placement: tries per sphere before the fill box is made taller.
DEM_FILL_TRIES = 200
#: Fill box: initial height as a multiple of the height of a dense bed (packing fraction 0.6).
DEM_FILL_HEIGHT_FACTOR = 2.5
#: Runs with fewer spheres than this use one thread: a parallel region costs more than it saves
#: on a handful of spheres (and far more when the cores are shared).
DEM_PARALLEL_MIN_SPHERES = 256
#: numba threading layer for the DEM kernels (applied by dem.kernels unless the environment sets
#: NUMBA_THREADING_LAYER): on the project's 2-core machines OpenMP scales (1.5e7 vs 9.7e6
#: particle-steps/s, sphere-bed, 2 vs 1 thread) where TBB and workqueue make 2 threads 2-3x
#: slower than one (a parallel region costs them tens of microseconds; a step has two).
DEM_THREADING_LAYER = "omp"
#: A running case writes checkpoint.npz every this many cycles (and on SIGINT/SIGTERM).
DEM_CHECKPOINT_EVERY = 10
#: ``run.settle_cycles = "auto"``: driven cycles before the transient test is first made (the
#: MSER rule needs a few cycles on either side of a transient's end) and the most it waits.
DEM_AUTO_SETTLE_MIN_CYCLES = 6
DEM_AUTO_SETTLE_MAX_CYCLES = 200
#: ... and what MSER keeps of the settling series may show a least-squares trend of at most this
#: many of its standard errors (dem.physics.measure.trend): MSER alone ended the screw bed's
#: settle at its minimum while the bed was still speeding up (validation/steadiness, beds).
DEM_AUTO_SETTLE_TREND_Z = 2.0
#: A measured series whose trend exceeds this many standard errors is not steady: with
#: settle_cycles = "auto" the run measures run.cycles more (at most DEM_STEADY_MAX_EXTENSIONS
#: times) and says so; with a fixed settle it says so. 3: a steady series of 20-30 cycles is
#: called unsteady in 1-28 % of runs (lag-1 correlation 0-0.8, validation/steadiness).
DEM_STEADY_Z = 3.0
DEM_STEADY_MAX_EXTENSIONS = 2
#: ... and a series whose second half spans at most this fraction of A omega cos(phi) is steady
#: (a single grain converging geometrically onto its orbit has no noise for MSER to weigh).
DEM_AUTO_SETTLE_TOLERANCE = 1e-4
#: ... and it settles for at least this many times the cycles the floor's friction needs to take
#: the drive's start-up velocity out of a grain (a lower bound: friction_relaxation_cycles in
#: dem.physics.drive); below that a steady series can be the start-up itself (a grain with little
#: friction keeps its start-up velocity for many cycles). An explicit run.settle_cycles below it
#: is warned about. 2 leaves every shipped case's settle as it was (1.8 and 3.0 cycles).
DEM_FRICTION_RELAX_FACTOR = 2.0
#: OpenMP wait policy for the DEM kernels' threads, applied by dem.kernels unless the environment
#: sets OMP_WAIT_POLICY; None leaves libgomp's default (spin, then sleep). A trade-off measured on
#: the 2-core machines (sphere-bed, 2 threads, 2026-11-21): with both cores free the default gave
#: 1.7e7 particle-steps/s and PASSIVE 0.7-0.9e7; with another process holding a core the default
#: (and ACTIVE) fell to 0.08-0.27e7 while PASSIVE kept 0.7-0.9e7. The thread guard below now
#: handles a shared machine (validation/performance/threads_shared.py).
DEM_OMP_WAIT_POLICY: str | None = None
#: Thread guard (dem.engine.threads): with more than one thread, try the other choice (one thread,
#: or back to N) after this many chunks of DEM_CHECK_INTERVAL steps, the wait doubling (up to 8x)
#: while the choice holds, and keep the faster; False leaves the thread count alone.
DEM_THREAD_GUARD = True
DEM_THREAD_GUARD_PERIOD = 8
#: ... timing only chunks of at least this many steps ...
DEM_THREAD_GUARD_MIN_STEPS = 100
#: ... and running a try of the other choice for this many steps (a try on N threads beside busy
#: processes runs many times slower than one thread: a short try keeps its cost small).
DEM_THREAD_GUARD_TRY_STEPS = 100
#: After a try that confirmed the choice, the next waits until the tries have cost at most this
#: fraction of the steps run (a try of N threads that ran 20x slower than one waits about 190
#: chunks) ...
DEM_THREAD_GUARD_TRY_COST = 0.02
#: ... and at most this many chunks (so that a machine that frees up is noticed).
DEM_THREAD_GUARD_MAX_WAIT = 400

#: Solid fraction assumed for a resting bed where depth and grain count are converted
#: (``particles.layers``, ``bed_height``, ``mass_per_area``: :mod:`dem.scene.depth`) and for the
#: stiffness rule's bed height (:mod:`dem.run.stiffness`); random packings of spheres lie at
#: 0.55-0.64, of elongated grains lower.
BED_PACKING = 0.6

#: Drive cycles run after the measured ones to sample the grains in flight by phase
#: (``output.flight_phases``, :mod:`dem.run.flight`): the bed's state, not its transport, so
#: it is not part of the measured velocity.
DEM_FLIGHT_CYCLES = 2

#: Seconds over which the thread guard samples the CPUs' idle time before a run starts
#: (:func:`dem.engine.threads.busy_cores`): long enough for a busy core to show (the kernel
#: counts in 10 ms ticks), short beside a run.
DEM_THREAD_GUARD_SAMPLE_S = 0.25
