"""Benchmark: flying the suggested manoeuvres against the paper's trajectory (issue 27, acceptance 3).

For each simulator preset (``paper``: two drones; ``ground``: a static station and a drone) three
flights are simulated with the preset's antennas, wind, pose estimator and radio, synchronised
as real logs are, and their statistics accumulated at a fixed SH order in 2-s steps of flight
time:

- **reference**: the preset's learning units (``paper``: the paper's three units; ``ground``:
  its passes, since a static station cannot fly the paper's vertical circle);
- **suggested**: the reference's first seconds until ``rplearn live`` has its first suggestion
  (:func:`live_start_s`: 2 s; 10 s before, an arbitrary choice), then, one after another, the
  manoeuvre :func:`rplearn.analysis.manoeuvres.rank_manoeuvres` ranks first from the statistics
  and the latest poses so far (each flown in the simulator from where the last one ended);
- **optimized**: the plan of ``rplearn trajectory --optimize``
  (:func:`rplearn.analysis.manoeuvres.greedy_plan` from the prior alone, before any flight),
  flown unit after unit.

The spread is each node's posterior pattern spread over the *target directions* (the points of a
1,024-point Fibonacci grid within 10 deg of a direction the complete reference flight saw: about
the whole sphere for ``paper``, a few percent for ``ground``), the node's mean removed, under one
error model for all three flights, learned by ``fit --degree auto`` from the complete reference
flight (its cross-validated smoothing times the penalty's scale at the chosen order, as
:mod:`rplearn.models.own_posterior` continues it). ``--posterior inflated`` (default): the fit's
noise times its variance inflation, for every part of the posterior. ``--posterior honest``
splits what that fit learned about its own errors into parts that behave differently under
different flights (:class:`~rplearn.analysis.manoeuvres.ManoeuvreOptions`): the *noise* is the
fit's residual noise (white: more packets average it out); the *prior's* variance is the
inflation times what the smoothing implies (``prior_variance_factor``: where the data are thin
the fit's error is the larger prior's, however many packets it has elsewhere); the held-out
*misfit* per node is the structure the order cannot represent, an offset per direction cell
(``misfit_std_db``, :mod:`rplearn.analysis.manoeuvre_cells`: looking again at the same
directions does not average it out); and the drifting error below. Measured over seeds 0-4 (20
planner cells, one thread): the plans' worst error exceeded the reference's by +0.13 dB on average
(+0.23 inflated), 9 of 20 within +0.05 dB (6), time ratio 0.67x (0.75x), both checks 4 of 20 (3):
within the cells' scatter, and the ranking about 2.2x slower (311 candidates), so it is not the
default (``rplearn live`` and ``trajectory --optimize`` keep the inflated model too). ``--prior-std DB`` instead states a
smoothness prior of that spread over the sphere
(:func:`~rplearn.analysis.manoeuvres.prior_penalty_weight`) with the simulator's nominal noise.
The ranking uses the same model (``--hyper reference``; see below).

**What the planners know** (``--hyper``). The spreads above are always read under the error
model of the complete reference flight's fit: it is the benchmark's yardstick, the same for all
three flights. What the planners (the suggested flight's ranking, ``--ranker reference``, and
the optimized plan's :func:`~rplearn.analysis.manoeuvres.greedy_plan`) are *given* is another
matter, for a user plans before this flight's reference exists (:func:`_planning_options`):

| ``--hyper`` | noise, prior (smoothing), drifting error | stands for |
| --- | --- | --- |
| ``reference`` (default) | the fit of this flight's reference, its blocks | an oracle: this flight's own figures |
| ``previous`` | ``--from-model``: an earlier flight's fit (the reference's units, seed :data:`PREVIOUS_SEED`) | a user with an earlier fit |
| ``cli`` | ``trajectory --optimize``'s defaults: 4.2 dB, a 6-dB smoothness prior, no drift | a user with no fit at all |
| ``flags`` | ``previous``'s noise and drift, the CLI's 6-dB prior (``--from-model --prior-std 6``) | a user overriding its smoothing |

Under each the planners keep the benchmark's target directions, candidates, packet rate (the
radio's, as ``--packet-rate`` gives it) and, with ``--tilt``, the tilt: what the user wants to
learn and what the radio and vehicles do, not a fit's figures. ``--ranker live`` ranks with its
own refits, and with ``--hyper previous`` as ``rplearn live --from-model`` ranks: the earlier
flight's model file (:func:`rplearn.workflows.live_advice.earlier_fit`) gives the ranking's noise,
smoothing and drift while the session has learned fewer samples than that fit (``reference``,
``cli`` and ``flags`` leave live's ranking as it is), and ``--bound`` is computed under the yardstick's model.
With ``--prior-std DB`` the prior is stated, and ``previous`` differs from ``reference`` only in
the drifting error. Measured (seeds 0-4, one draw, one thread; ``docs/guides/calibration-plan.md``,
"What it buys"): the optimized plan's time ratio on ``paper`` 0.53-0.62x (``reference``),
0.53-0.63x (``previous``), 0.50-0.57x (``flags``), 0.94-1.03x and once short of 2 dB (``cli``: the
paper's own unit first); on ``ground`` seeds 0 and 2 every plan but ``reference``'s ends short of
2 dB (2.02-2.75 dB: the earlier flight's fit was less noisy than theirs). ``--planners optimized``
flies the optimized plan alone (no suggested flight), ``--planners suggested`` the suggested flight alone.

**What the error check can and cannot tell** (``--budget``: each flight's samples split into the
truth at the logged directions, the pointing part and the rest, each fitted alone; seeds 0-2): at a flight's 2-dB point its worst
per-node error is about 1.3-2.6 dB, of which the fit's bias (smoothing 0.5-1.7 dB, aliasing of the
structure above the order 0.5-2.1 dB, truncation 0.75-1.0 dB common to all flights), the heading
error's pointing part 0.2-1.35 dB and the fading 0.1-0.7 dB; the realisation alone moves it by
about 0.5 dB: two plans of the same length (paper seed 0, 154 s) gave 1.59 and 2.15 dB, the same
suggested flight to within 1 s (paper seed 1, 229/230 s) 1.67 and 2.22 dB. A single flight's
error against a 0.05-dB tolerance is therefore close to a coin flip even for a calibrated
posterior, which is why the check is made on the *expected* error (below). One BLAS thread is pinned (``RPLEARN_THREADS=1`` unless set) so that a run repeats
figure for figure: with the load-dependent thread policy the ranking's near-ties fell
differently between runs. At the point where each flight first reaches 2 dB it is
recomputed through :func:`rplearn.models.own_posterior.own_pattern_posterior` (the fit's own
posterior, under the solver's gauge) and the two are printed. The pattern error at that point is
:func:`rplearn.analysis.pattern_error.pattern_errors_db` of the fit from the same statistics and
prior against the simulator's truth over the target directions.

Flight time counts the units' durations and the time to reach each manoeuvre's start, not the
battery gaps between units. The electronics offsets and the dropouts of the presets are off in
all three flights alike (one flight's unit cannot carry a dropout drawn for the whole campaign).

**The drifting error** (``--correlated``, :mod:`rplearn.core.lsq.block_sums`): each flight also
keeps its sums per 5-s time block, and every spread and ranking carries an error drifting over
seconds (the simulator's heading error wanders over about 5 s): ``reference`` (default) takes its
size, like the noise, from the complete reference flight
(:func:`~rplearn.analysis.manoeuvres.correlated_error_std_db`); ``own`` estimates it from each
flight's own blocks so far, as ``rplearn live`` does; ``off`` is the white-noise posterior
(the benchmark as it was).

**The expected error** (``--draws N``, default 5): a flight plan is a commanded trajectory and a
flight time, and its pattern error at its 2-dB point is a random variable of the noise, fading,
wind and pose errors it meets, not of the plan. Each flight's plan as flown (the reference's
units; the suggested flight's start and manoeuvres; the optimized plan's units; each with its
lead time) is therefore flown again ``N`` times under independent draws (seeds
``seed * 1000 + 300 * plan + k + 100000 * draw``, never the first draw's, and never two plans'
alike: the suggested flight's start is the reference's first unit), and each draw's statistics are cut
at the flight time at which the first draw reached 2 dB (the spread depends on the directions
flown, not on the noise: the draws' largest spread there is printed and stays within about
+-0.15 dB of 2). The first draw is left out of the mean: the suggested flight's choices and every
flight's stopping time were made from it, so it is not an independent draw of its plan. The
plans' expected worst per-node errors are compared through the mean over the draws and its
standard error ``s.e. = std / sqrt(N)``; the draws of different plans are independent, so the
difference of two means has the standard error ``sqrt(se_plan^2 + se_ref^2)``, and "no worse"
is ``mean_plan <= mean_ref + 2 * sqrt(se_plan^2 + se_ref^2)`` (:data:`ERROR_SE`): a plan fails
when its draws show it worse at about the 2-sigma one-sided level (2.3 % for a plan exactly as
good as the reference). It is a test of "not shown worse", whose power grows with ``N``: with
5 draws and a per-draw spread of 0.1-0.25 dB the tolerance is 0.15-0.35 dB. The single-draw
figures and the old check (+0.05 dB) are still printed beside it.

Measured (seeds 0-2, one thread, 5 draws): the expected-error check passes 11 of 12 cells (the
single-draw check 5); plan minus reference, paper +0.31/+0.35, -0.07/+0.26, -0.37/+0.20 dB
(suggested/optimized per seed), ground +0.24/+0.32, -0.17/-0.04, -0.04/+0.02 dB; pooled over the
seeds paper suggested -0.05 +- 0.09, optimized +0.27 +- 0.15, ground +0.01 +- 0.07 and
+0.10 +- 0.09 dB (s.e.): no excess shown, though the paper's optimized plan leans worse. The one
miss, paper seed 0 suggested, +0.31 dB against 0.24. The time criterion fails 6 of 12 (paper
0.60-0.74x, 5 of 6; ground seed 0 suggested 0.68x), so 6 of 12 cells meet both.

**Why the time is missed** (the planner's own predicted spread over the commanded geometry,
paper seed 0; not enforced): the 2-dB target lies near the floor the spread approaches (the
reference flight's predicted spread is 1.67 dB after 740 s, 1.51 without the drifting error), so the greedy plan
takes 110 s to 2.45 dB and 90 s more to 2.0 dB; the variance left then sits in the caps around
each node's poles (the peer straight above or below: 3.5 dB RMS at -90..-60 deg against 1.7 dB
at 0..30 deg). Not the transit (none for manoeuvres from where the drone is, a few seconds
for the library's units), not the
candidates' distances or revisits (the same plan), not myopia (a two-step lookahead over the
top 4 gave 0.86x predicted against 0.80x). Orbits and climbs to +-85 deg cut the predicted
ratio on seeds 0/1/2 from 0.80/0.59/0.63 to 0.71/0.45/0.59, but flown they gave 0.61/0.62,
0.62/0.64, 0.67/0.70 (was 0.72/0.74, 0.60/0.62, 0.62/0.67): no default changed on that.
Counting, on top, only the time until a manoeuvre reaches the target (the flight stops there)
was as mixed (paper 0.59/0.65, 0.62/0.64, 0.66/0.66; ground seed 1 suggested 0.56x -> 0.63x).
The prediction itself is far off for some flown flights (paper seed 1: the reference's
predicted 2-dB time 572 s, flown 326 s; the cause, e.g. the tilt in the wind or the pose
errors widening the directions seen, is not measured).

**Faster turns and arcs** (``--yaw-rate 45``, ``--arcs``; measured, not the default). The
drifting error is one offset per link and 5-s block, so the spread falls with the number of
blocks that see each direction and with how wide each block's sweep is: at the candidates'
30 deg/s a block sees 150 deg of a ring, at 45 deg/s (near the 47-deg/s peak of the paper's own
units) 225 deg. Arcs over the anchor's zenith or under its nadir (``CandidateOptions.arcs``)
reach the pole caps directly. Time ratio to 2 dB and expected-error difference (plan minus
reference, dB; ``*``: a check missed), seeds 0-2, one thread, 5 draws, load 6-13 on 2 cores:

| cell | 30 deg/s (default) | 45 deg/s + arcs | 45 deg/s |
| --- | --- | --- | --- |
| paper 0 suggested | 0.72* / +0.31* | 0.63* / +0.18 | 0.57 / +0.48* |
| paper 0 optimized | 0.74* / +0.35 | 0.62* / +0.17 | 0.61* / +0.25 |
| paper 1 suggested | 0.60 / -0.07 | 0.67* / -0.12 | 0.65* / -0.15 |
| paper 1 optimized | 0.62* / +0.26 | 0.57 / -0.21 | 0.69* / +0.07 |
| paper 2 suggested | 0.62* / -0.37 | 0.63* / -0.38 | 0.63* / -0.38 |
| paper 2 optimized | 0.67* / +0.20 | 0.70* / -0.33 | 0.62* / -0.44 |
| ground 0 suggested | 0.68* / +0.24 | 0.63* / -0.37 | 0.63* / -0.37 |
| ground 0 optimized | 0.58 / +0.32 | 0.47 / +0.33* | 0.47 / +0.33* |
| ground 1 suggested | 0.56 / -0.17 | 0.50 / +0.05 | 0.50 / +0.05 |
| ground 1 optimized | 0.58 / -0.04 | 0.60 / -0.16 | 0.60 / -0.16 |
| ground 2 suggested | 0.52 / -0.04 | 0.55 / -0.01 | 0.55 / -0.31 |
| ground 2 optimized | 0.42 / +0.02 | 0.38 / +0.12 | 0.37 / +0.19 |
| both checks | 6 of 12 | 5 of 12 | 4 of 12 |
| mean time ratio paper / ground | 0.66 / 0.56 | 0.64 / 0.52 | 0.63 / 0.52 |
| seeds 3-4 (not tuned on), both checks | 2 of 8 | 4 of 8 | 3 of 8 |

(The default's ground times were measured again with ``--draws 0``, its errors are the table
above.) On seeds 3-4 the default gave paper 0.75/0.68x (suggested/optimized, seed 3) and
0.66/0.57x (seed 4), ground 0.58/0.98x and a degenerate seed 4 (the reference reaches 2 dB at
4 s, inside the suggested flight's start, then 10 s); 45 deg/s with arcs 0.66/0.55, 0.60/0.56, ground
0.48/0.91; 45 deg/s 0.52/0.58, 0.60/0.61, ground 0.48/0.91. Faster turns shorten the mean time,
but the single-flight times move by about +-0.05 from one variant to the next (paper seed 1
suggested 0.60 -> 0.65-0.67x, seed 0 0.72 -> 0.57x), and the shorter flights stop with fewer
samples, so the error check, which is made at each flight's own 2-dB point, misses instead
(paper seed 0 suggested +0.48 dB at 0.57x). The arcs were chosen (a 33-s arc at 6 m, transit
included) but did not pay for their time (paper seed 0, one draw: 0.63/0.62x with them at
45 deg/s against 0.57/0.61x without; 0.71/0.68x at 30 deg/s against 0.72/0.74x). Neither is the
default.

**Where the time goes, and the wind's tilt** (``--tilt``; seeds 0-2, one thread; load 7-9 on 2
cores). Each suggested step prints the ranking's predicted largest spread before and after it and
the flown one: with the drones' steady lean in the wind modelled
(:attr:`~rplearn.analysis.manoeuvres.ManoeuvreOptions.steady_accel_enu_m_s2`, estimated from the
start's poses by :func:`~rplearn.analysis.manoeuvres.steady_tilt_accel`: 14.9-16.6 deg on
``paper``, whose 10-m/s wind tilts the drones by 12-15 deg; 0.2-0.6 deg on ``ground``, which has
none) the prediction of every paper step was within 0.08 dB of the flight (45 steps, seeds 0-4:
flown minus predicted -0.08 to +0.04 dB; paper seed 0: 4.64 -> 4.43 predicted, 4.37 flown;
3.17 -> 2.70, 2.65; 2.18 -> 2.03, 2.00); on ``ground`` the flights did 0.01-0.29 dB better than
predicted (11 steps). The ranking is therefore
not aiming at a spread the flight does not give, and the spread it ranks by is the benchmark's
(one model for both). Nor does the target hinge on a few unreachable directions: with the
drift's part left out (the white posterior alone), the reference flight's spread is spread over
the elevations in proportion to their share of the targets (paper seed 0, every band of 30 deg
holds 12-22 % of the variance after each unit), and the white part is 85 % of the total at the
2-dB point (reference, paper seed 0: 1.59 of 1.86 dB for node B). What the curves show (spread
over time, printed per flight) is two phases. The planned flights cover fast: paper seed 0
suggested/optimized reach 2.48/2.33 dB at 81/101 s, where the reference stands at 3.70 dB
(its first 140 s teach node A, 1.94 dB at 125 s, while node B stays at 3.6 dB). Then all
flights enter a tail where the spread falls as the packets accumulate, ``1/s^2`` growing about
linearly with time, and the planned flights' tail is the slower one where they miss: from about
2.45 dB to 2.0, ``d(1/s^2)/dt`` was 1.09/1.01e-3 per dB^2 and s (suggested/optimized) against
the reference's 1.77e-3 (paper seed 0: 80/65 s against 44 s), seed 2 optimized 1.39e-3 against
1.99e-3; where the planners pass, their tail matched or beat the reference's (seed 1:
1.18/1.07e-3 against 0.69e-3; ground 1.4-7.1e-3 against 1.0-2.6e-3). The reference's fast tail
is its unit's second half, long full sweeps that teach node B, which the first half left at
3.6 dB; the greedy's tail is a series of 12-34-s climbs, turns and orbits whose predicted gain
per second, the best in the set at each step and flown as predicted, is lower. Modelling the tilt
did not change that (it changes which of the near-tied candidates comes first):

| cell | default | ``--tilt`` |
| --- | --- | --- |
| paper 0 suggested / optimized | 0.72* / +0.31*, 0.74* / +0.35 | 0.71* / +0.29*, 0.68* / +0.68* |
| paper 1 suggested / optimized | 0.60 / -0.07, 0.62* / +0.26 | 0.67* / +0.04, 0.63* / -0.06 |
| paper 2 suggested / optimized | 0.62* / -0.37, 0.67* / +0.20 | 0.65* / -0.32, 0.65* / +0.35 |
| ground 0-2 | as the default | the same figures (5 of 6) |
| both checks | 6 of 12 | 5 of 12 |
| paper seeds 3-4 (not tuned on), time only | 0.75/0.68, 0.66/0.57 | 0.63/0.63, 0.58/0.68 |

(time ratio / expected-error difference in dB, suggested then optimized; ``*``: a check missed;
5 draws.) The mean paper time ratio over seeds 0-2 is 0.66 either way, 0.67 -> 0.63 on seeds
3-4: within the +-0.05 the single flights move by from one variant to the next, so ``--tilt`` is
not the default (``rplearn live`` and ``trajectory --optimize`` fly level references). What would
reach 0.6x on ``paper`` is a higher information rate in the tail, not a better-aimed first
phase; the candidates offered (30-deg/s turns, climbs, orbits, the paper's units, and, measured
above, 45-deg/s turns and arcs) do not offer one, so the 60 % criterion stays missed in the
cells listed. Scoring by the largest node's spread (``--aggregate max``, the stop criterion's
own combination, instead of the nodes' RMS) moved the single flights as much and the mean not
at all (``--draws 0``, time ratios suggested/optimized: paper 0.64/0.62, 0.77/0.66, 0.68/0.63 on
seeds 0-2, mean 0.67 against 0.66; ground 0.68/0.52, 0.80/0.78, 0.52/0.48, ground seed 1 from
0.56/0.58; paper seeds 3-4 0.56/0.62, 0.58/0.63): the time check passes 3 of 12 cells against 6,
so the RMS stays. Across the variants measured (faster turns, arcs, the tilt, the max score) a
single cell's ratio moves by up to +-0.2 from one to the next while the paper mean stays at
0.63-0.67: the cells that pass or miss by a few hundredths do so by which of the near-tied
candidates comes first.

**Loop sweeps and the information rate** (default; ``--no-sweeps --rate spread``: as before; seeds 0-2, one
thread, 5 draws, load 3-11 on 2 cores). A loop sweep (:mod:`rplearn.plan.sweeps`) is the paper
unit's half: ``n`` of its vertical circles (each crosses both nodes' pole caps) with one drone's
heading stepping, or both drones' (the second at twice the first's step, so that their relative
heading changes too), offered where the library's units are. Alone, the greedy ranking took
them in the tail (paper seed 0: 2 loops with B turning, 38 s, predicted 2.43 -> 2.21 dB, flown
2.18) but not often enough to matter: paper 0.63*/+0.49*, 0.69*/+0.12; 0.59/-0.08, 0.67*/-0.09;
0.63*/-0.38, 0.69*/+0.10 (1 of 6 paper cells, as the default). The ranking's measure was the
other half: the reduction of the spread per second favours short manoeuvres even at the same
information rate (under a steady rate ``1/s^2`` grows linearly, so ``s`` falls as ``1/sqrt(t)``
and a manoeuvre twice as long gains less than twice the dB), so the long sweeps never won
against the 12-s climbs and turns. ``ManoeuvreOptions.rate = "information"`` ranks by the growth
of the inverse square of the combined spread per second instead, which does not penalise length:

| cell | default | sweeps | sweeps + information rate |
| --- | --- | --- | --- |
| paper 0 suggested / optimized | 0.72* / +0.31*, 0.74* / +0.35 | 0.63* / +0.49*, 0.69* / +0.12 | 0.63* / +0.41, 0.60 / +0.53* |
| paper 1 suggested / optimized | 0.60 / -0.07, 0.62* / +0.26 | 0.59 / -0.08, 0.67* / -0.09 | 0.59 / -0.17, 0.52 / -0.03 |
| paper 2 suggested / optimized | 0.62* / -0.37, 0.67* / +0.20 | 0.63* / -0.38, 0.69* / +0.10 | 0.65* / -0.27, 0.60 / -0.19 |
| ground 0 suggested / optimized | 0.68* / +0.24, 0.58 / +0.32 | (no sweeps without two drones) | 0.68* / +0.24, 0.58 / +0.32 |
| ground 1 suggested / optimized | 0.56 / -0.17, 0.58 / -0.04 | | 0.80* / -0.30, 0.58 / -0.04 |
| ground 2 suggested / optimized | 0.52 / -0.04, 0.42 / +0.02 | | 0.52 / -0.04, 0.42 / +0.02 |
| both checks | 6 of 12 | paper 1 of 6 | 7 of 12 |
| mean time ratio paper / ground | 0.66 / 0.56 | 0.65 / - | 0.60 / 0.60 |
| seeds 3-4 (not tuned on), both checks | 2 of 8 | (time only, paper: 0.75/0.57, 0.67/0.59) | 3 of 8 |

(time ratio / expected-error difference in dB, ``*``: a check missed; the paper optimized plan
now passes the time check on every seed, at 0.52-0.60x.) The information rate moved the paper
flights' mean from 0.66 to 0.60x; on ``ground`` it changed only seed 1's suggested flight (0.56 ->
0.80x: a 58-s reference leaves no room for a longer first move), and seed 0 optimized paper plan
now misses the error check (+0.53 dB against a tolerance of 0.34: the shorter flight stops with
fewer samples, as with the faster turns above). On seeds 3-4 (not tuned on; the default's
figures from the table above) paper 0.62* / +0.38*, 0.58 / +0.31* (seed 3) and 0.56 / -0.18,
0.55 / +0.69 (seed 4, tolerance 0.71), ground seed 3 0.58 / -0.01, 0.98* / +0.12 and the
degenerate seed 4 3.00* / -0.18, 0.50 / +0.35*. The information rate alone, without the sweeps,
did not help (``--draws 0``, time only, paper: 0.63/0.64, 0.65/0.63, 0.73/0.73; mean 0.67): the
two work together, the sweeps offering a long manoeuvre with a high tail rate and the measure
letting it win. Both are the defaults (``CandidateOptions.sweeps``, ``ManoeuvreOptions.rate``;
``rplearn live`` and ``trajectory --optimize`` use them): 7 of 12 cells against 6 on seeds 0-2,
3 of 8 against 2 on seeds 3-4. The gain is small against the cells' scatter (a single cell
moves by up to +-0.2 from one variant to the next) and the paper seed 0 cells and three ground
suggested cells still miss; ``--rate spread`` and ``CandidateOptions(sweeps=False)`` give the
previous ranking.

**Best prefixes** (``--prefixes 4``; the default ``--prefixes 1``: whole manoeuvres;
seeds 0-4, one thread, 5 draws, load 8-18 on 2 cores). A candidate is also scored by its first
quarter, half and three quarters (:attr:`~rplearn.analysis.manoeuvres.ManoeuvreOptions.prefixes`,
whole 5-s blocks, at least 10 s) and ranked by its best; a winning prefix is flown alone
(:class:`rplearn.plan.prefix.PrefixUnit`) and the ranking starts again where it ends. A long
candidate whose later part repeats what its first part taught (the second lap of an orbit or a
720-deg turn, the end of a ground pass or a loop sweep) no longer has to be flown whole to win,
nor lose to a short one by its tail: ground seed 1 suggested flew three 10-s prefixes (a turn,
an orbit at +75 deg, a turn) to 2 dB at 32 s where it flew a 15-s climb and a 42-s pass to
46 s. Time ratio and expected-error difference (plan minus reference, dB; ``*``: a check missed):

| cell | whole (default before) | best prefix (default) |
| --- | --- | --- |
| paper 0 suggested / optimized | 0.63* / +0.41, 0.60 / +0.53* | 0.62* / +0.12, 0.56 / +0.22* (tol 0.21) |
| paper 1 suggested / optimized | 0.59 / -0.17, 0.52 / -0.03 | 0.50 / -0.09, 0.56 / -0.24 |
| paper 2 suggested / optimized | 0.65* / -0.27, 0.60 / -0.19 | 0.57 / -0.26, 0.58 / -0.46 |
| ground 0 suggested / optimized | 0.68* / +0.24, 0.58 / +0.32 | 0.68* / +0.20* (tol 0.18), 0.45 / -0.07 |
| ground 1 suggested / optimized | 0.80* / -0.30, 0.58 / -0.04 | 0.54 / -0.13, 0.42 / -0.01 |
| ground 2 suggested / optimized | 0.52 / -0.04, 0.42 / +0.02 | 0.48 / -0.07, 0.60* (119 of 197 s) / -0.19 |
| both checks, seeds 0-2 | 7 of 12 | 8 of 12 |
| mean time ratio paper / ground, seeds 0-2 | 0.60 / 0.60 | 0.57 / 0.53 |
| paper 3 suggested / optimized | 0.62* / +0.38*, 0.58 / +0.31* | 0.54 / +0.09, 0.59 / +0.38* (tol 0.24) |
| paper 4 suggested / optimized | 0.56 / -0.18, 0.55 / +0.69 | 0.53 / -0.09, 0.55 / +0.03 |
| ground 3 suggested / optimized | 0.58 / -0.01, 0.98* / +0.12 | 0.58 / -0.06, 0.65* / +0.04 |
| ground 4 suggested / optimized | 3.00* / -0.18, 0.50 / +0.35* | 3.00* / -0.21, 0.50 / +0.36* (tol 0.17) |
| both checks, seeds 3-4 (not tuned on) | 3 of 8 | 4 of 8 |

(The "whole" column is the table above's last one, measured before; its paper seed 0 and ground
seed 1 times were measured again with ``--draws 0`` in this run and repeated figure for figure.)
Mean expected-error difference over seeds 0-2, suggested / optimized: paper -0.08 / -0.16 dB
(was -0.01 / +0.10), ground 0.00 / -0.09 (was -0.03 / +0.10). What got worse: ground seed 2
optimized now misses the time by 1 s of 197 (0.42 -> 0.60x: its plan is a string of short
prefixes), ground seed 0 suggested now misses the error check by 0.02 dB (+0.24 -> +0.20 dB, but
the tolerance fell from its draws' smaller scatter), and paper seed 0 optimized still misses it
(+0.53 -> +0.22 dB against 0.21). Paper seed 0 suggested still misses the time (0.62x): its
tail is the slow phase described above. A ranking scores the prefixes of candidates longer than
about 13 s besides the whole: 1.41x the time of whole manoeuvres only (the smoke preset's
statistics at SH-10, 267 candidates, best of 3 alternately in one process, load 9-18). Finer
prefixes were measured once and not pursued (``--prefixes 8``, ``--draws 0``, the cut then
rounded a row later: ground seed 0 optimized 0.52 -> 0.74x, seed 1 suggested 0.65 -> 0.61x
against ``--prefixes 4`` in the same state).

**The braking after a cut** (measured after the table above): a prefix cut mid-orbit or
mid-turn leaves the vehicle at cruise speed or yaw rate, and the table's "best prefix" column
counted no time to stop (1.5 s at 1.5 m/s and 1 m/s^2, 0.5 s at 30 deg/s and 60 deg/s^2). Once
:attr:`rplearn.plan.prefix.PrefixUnit.brake_s` is part of a prefix's duration (in the ranking,
the plan's clock and this benchmark's flight time; no samples while braking), ``--prefixes 4``
gives (time ratio, expected-error difference; same settings, load 5-18):

| cell | best prefix, braking counted |
| --- | --- |
| paper 0 suggested / optimized | 0.58 / +0.22, 0.65* / +0.20 |
| paper 1 suggested / optimized | 0.54 / -0.11, 0.57 / -0.20 |
| paper 2 suggested / optimized | 0.63* / -0.46, 0.63* / -0.40 |
| ground 0 suggested / optimized | 0.68* / +0.24, 0.49 / -0.10 |
| ground 1 suggested / optimized | 0.95* / -0.15, 0.46 / -0.02 |
| ground 2 suggested / optimized | 0.50 / -0.07, 0.63* / -0.23 |
| both checks, seeds 0-2 | 6 of 12 (whole manoeuvres: 7) |
| paper 3 suggested / optimized | 0.54 / +0.30, 0.53 / +0.27* (tol 0.21) |
| paper 4 suggested / optimized | 0.56 / -0.10, 0.62* / -0.14 |
| ground 3 suggested / optimized | 0.58 / -0.06, 0.66* / +0.04 |
| ground 4 suggested / optimized | 3.00* / -0.21, 0.50 / +0.36* (tol 0.17) |
| both checks, seeds 3-4 | 3 of 8 (whole manoeuvres: 3) |

With its stops paid for, scoring prefixes is no better than flying whole manoeuvres (6 of 12
against 7 on the tuning seeds, 3 of 8 alike on the held-out ones): the gain of the column
above was the uncounted braking and the near-ties it moved. So whole manoeuvres stay the default
of ``rplearn live`` and ``trajectory --optimize`` (``ManoeuvreOptions.prefixes = 1``), and the
default's figures are those of the "whole" column.

**Ranking by the time to the target** (``--lookahead 4``; the default ``--lookahead 0``: by rate;
seeds 0-4, one thread, 5 draws, load 7-15 on 2 cores). The information rate is the right order
while the rate the flight goes on at afterwards does not depend on the manoeuvre chosen now; it
does (a short manoeuvre that takes the cheapest directions leaves a slower one for the next
step), and near the target the flight stops where the spread is reached, so what counts is the
time to get there. ``ManoeuvreOptions.lookahead = k``
(:mod:`rplearn.analysis.manoeuvre_lookahead`) ranks the best ``k`` by rate again by their
estimated flight time to 2 dB: each one's time, then the information deficit
``1/T^2 - 1/a^2`` it leaves over the best information rate among the candidates flyable from
where it ends, on the posterior it leaves (a two-step look-ahead, judged on time to the target;
the earlier one over the top 4 was judged on the predicted ratio only); a candidate that reaches
the target scores the fraction of its time at which it does (the flight stops there; a first
version scored its whole time: the same times on ground seeds 0-1). It chose longer manoeuvres in the
tail (paper seed 1: a 5-loop sweep, 86 s, predicted 2.52 -> 2.21 dB, flown 2.05) and cost
``k`` more rankings per step (5.8x the ranking's time at ``k = 4``: smoke statistics at SH-10,
267 candidates, best of 3 alternately in one process, load 10). Time ratio and expected-error
difference (plan minus reference, dB; ``*``: a check missed):

| cell | by rate (default) | time to target, ``--lookahead 4`` |
| --- | --- | --- |
| paper 0 suggested / optimized | 0.63* / +0.41, 0.60 / +0.53* | 0.59 / -0.05, 0.66* / +0.34 |
| paper 1 suggested / optimized | 0.59 / -0.17, 0.52 / -0.03 | 0.61* (198 of 326 s) / -0.15, 0.51 / -0.22 |
| paper 2 suggested / optimized | 0.65* / -0.27, 0.60 / -0.19 | 0.64* / -0.27, 0.60* (135 of 224 s) / -0.43 |
| ground 0 suggested / optimized | 0.68* / +0.24, 0.58 / +0.32 | 0.52 / -0.10, 0.48 / +0.30* (tol 0.25) |
| ground 1 suggested / optimized | 0.80* / -0.30, 0.58 / -0.04 | 0.77* / -0.28, 0.91* / -0.13 |
| ground 2 suggested / optimized | 0.52 / -0.04, 0.42 / +0.02 | 0.51 / -0.22, 0.49 / -0.11 |
| both checks, seeds 0-2 | 7 of 12 | 5 of 12 |
| mean time ratio paper / ground, seeds 0-2 | 0.60 / 0.60 | 0.60 / 0.61 |
| paper 3 suggested / optimized | 0.62* / +0.38*, 0.58 / +0.31* | 0.57 / +0.25, 0.58 / +0.09 |
| paper 4 suggested / optimized | 0.56 / -0.18, 0.55 / +0.69 | 0.58 / -0.02, 0.66* / -0.02 |
| ground 3 suggested / optimized | 0.58 / -0.01, 0.98* / +0.12 | 0.67* / -0.10, 0.87* / +0.34 |
| ground 4 suggested / optimized | 3.00* / -0.18, 0.50 / +0.35* | 3.00* / -0.15, 0.50 / +0.37* (tol 0.19) |
| both checks, seeds 3-4 | 3 of 8 | 3 of 8 |

Ranked by the time to the target, the plans met both checks in 5 of 12 tuning cells against 7
(paper 2 of 6 against 3, ground 3 of 6 against 4) and in 3 of 8 held-out cells alike (paper 3 of
4 against 2, ground 0 of 4 against 1), at the same mean time ratio (paper 0.60, ground 0.61
against 0.60/0.60 on seeds 0-2). What improved: paper seed 0 suggested (0.63 -> 0.59x) and
ground seed 0 suggested (0.68 -> 0.52x) now pass, paper seed 3 both; the mean expected-error
difference over seeds 0-2 fell (paper -0.16 / -0.10 dB suggested/optimized, was -0.01 / +0.10;
ground -0.20 / +0.02, was -0.03 / +0.10). What got worse: on ground seed 1, whose reference
is short (58 s), both plans now take a 12-s turn and a 38-s orbit the look-ahead predicts to
reach 2 dB part-way (44 and 53 s flown), where the rate ranking reached it sooner as flown
(the optimized plan at 34 s); ground seed 3 suggested took 37 s against 33 (reference 56 s);
paper seed 1 suggested and seed 2 optimized miss by one 2-s step (198 of 196 s,
135 of 134 s), paper seed 4 optimized by 0.06x. It is therefore not the default (``rplearn live``
and ``trajectory --optimize`` rank by rate); ``ManoeuvreOptions(lookahead=4)`` with a target
(``floor_db``) gives it.

**Manoeuvres aimed at where the posterior is widest** (``--aimed 3``; ``--aimed -3``: rings;
the default ``--aimed 0``: the fixed candidates only; seeds 0-2, one thread, 5 draws, load 8-16
on 2 cores). Besides the fixed library, ``ManoeuvreOptions.aimed = k``
(:mod:`rplearn.analysis.manoeuvre_aimed`, :mod:`rplearn.plan.aimed`) offers, for each node's
``k`` target directions of largest posterior variance now (at least 30 deg apart), the
manoeuvres that make that node look along each: the mover climbs to where the peer appears at
the aim's elevation and turns through the aim's heading and 60 deg beyond it; a hovering anchor
turns through it while the mover climbs; an orbit at the aim's elevation; for a static station,
the drone flies to where the station sees it along the aim (the way there counted as lead time)
and turns a full circle there. 19-24 more candidates at ``k = 3`` (smoke statistics at SH-10:
291 against 267), a ranking 1.07x as long (best of 3 alternately in one process, load 10).
``k < 0`` (rings) aims the elevation only: full circles, no move to a station's aim. Time ratio
and expected-error difference (plan minus reference, dB; ``*``: a check missed):

| cell | default | aimed, ``--aimed 3`` | rings, ``--aimed -3`` |
| --- | --- | --- | --- |
| paper 0 suggested / optimized | 0.63* / +0.41, 0.60 / +0.53* | 0.64* / +0.53*, 0.63* / +0.47* | as the default |
| paper 1 suggested / optimized | 0.59 / -0.17, 0.52 / -0.03 | 0.60* (196 of 326 s) / -0.14, 0.62* / +0.03 | 0.61* / -0.15, 0.51 / -0.05 |
| paper 2 suggested / optimized | 0.65* / -0.27, 0.60 / -0.19 | 0.65* / -0.27, 0.62* / +0.06 | 0.65* / -0.27, 0.62* / +0.06 |
| ground 0 suggested / optimized | 0.68* / +0.24, 0.58 / +0.32 | 0.50 / +0.14, 0.62* / -0.00 | as the default |
| ground 1 suggested / optimized | 0.80* / -0.30, 0.58 / -0.04 | 0.80* / -0.28, 0.53 / +1.12* (tol 0.33) | as the default |
| ground 2 suggested / optimized | 0.52 / -0.04, 0.42 / +0.02 | 0.55 / -0.36, 0.81* / -0.69 | as the default |
| both checks, seeds 0-2 | 7 of 12 | 2 of 12 | 5 of 12 |
| ground 3, 4 (held out) | 0.58 / -0.01, 0.98* / +0.12; 3.00* / -0.18, 0.50 / +0.35* | 0.62* / +0.04, 0.98* / +0.12; 5.94* / -0.77, 0.50 / +0.43* | - |

(The default column is the one measured before; ground seed 0's default was flown again in this
run and repeated figure for figure, 0.68* / +0.24, 0.58 / +0.32.) The aimed candidates were
chosen, and their steps were flown as predicted (paper: within 0.02 dB), but they made the
flights slower or worse: on ``paper`` the ranking took short aimed steps (4-10 s: a climb while
the anchor turns through the aim, an orbit at -84 or +85 deg; 0.01-0.05 dB each: paper seed 0
suggested 2.38 -> 2.34 dB in 7 s, 2.17 -> 2.16 dB in 6 s) among the usual turns and sweeps,
since their information per second ranks high, and the flights reached 2 dB no sooner (mean
time ratio 0.63 against 0.60); on ``ground`` the moves to the station's widest direction
(24-43 s with the way there) were taken in every plan, which cut ground seed 0 suggested from 0.68x to 0.50x but made
the optimized plans slower (seed 2: 0.42 -> 0.81x, three such moves) or, where they reached the
spread soon, worse (seed 1: 0.53x at +1.12 dB: a turn in one place teaches the station a single
direction, which the smoothing spreads over its small target cap, so the predicted spread falls
faster than the error; our reading, not measured further). The rings (the same elevations, whole circles, no station moves) were
seldom taken (a 7-10-s orbit at +85 deg on paper; never on ground, whose figures are the default's)
but moved the paper flights' near-ties: paper seed 1 suggested 0.59 -> 0.61x, seed 2 optimized
0.60 -> 0.62x (the same plan as the aimed one), 5 of 12 cells. Held-out seeds were not flown for
them nor for the aimed variant on ``paper``: neither beat the default on the tuning seeds. So
neither is the default; ``ManoeuvreOptions(aimed=3)`` (or ``-3``) gives them.

**The optimal design over the candidates, and rankings that look at the end** (``--bound yes|only``,
``--design end|support``; :mod:`rplearn.analysis.manoeuvre_design`, :mod:`rplearn.analysis.manoeuvre_bound`;
seeds 0-2, one thread, ``--draws 0``, load 7-12 on 2 cores). Is 0.6x reachable with the candidates
offered? From the posterior after the suggested flight's start (then 10 s; and, for the optimized
plan, from the prior at the start poses), each candidate the ranking offers from there gives an
information matrix per second of its own flight (its feature rows, and with the drifting error
its 5-s blocks' sums per second), and the least total time ``sum(t_i)`` at which some split
``t_i >= 0`` over them brings every node's spread to 2 dB is solved (multiplicative, then
pairwise Frank-Wolfe steps on a smooth maximum over the nodes, the total re-solved after each
step; the way between manoeuvres, their order and whether a manoeuvre can be flown in part are
ignored). Ratios to the reference's flown time to 2 dB:

| cell | white-noise bound | design with the drift (gap) | greedy predicted (rate) | greedy flown (default) |
| --- | --- | --- | --- | --- |
| paper 0 suggested / optimized | 0.13 / 0.10 | 0.78 (0.07) / 0.67 (0.04) | 0.90 / 0.83 | 0.63 / 0.60 |
| paper 1 suggested / optimized | 0.15 / 0.13 | 1.11 (0.23) / 0.89 (0.09) | 0.81 / 0.74 | 0.59 / 0.52 |
| paper 2 suggested / optimized | 0.16 / 0.13 | 0.77 (0.04) / 0.65 (0.04) | 0.76 / 0.84 | 0.65 / 0.60 |
| ground 0 suggested / optimized | 0.11 / 0.03 | 0.53 (0.005) / 0.59 (0.01) | 0.83 / 0.80 | 0.68 / 0.58 |
| ground 1 suggested / optimized | 0.18 / 0.01 | 0.72 (0.04) / 0.70 (0.01) | 1.13 / 1.12 | 0.80 / 0.58 |
| ground 2 suggested / optimized | 0.10 / 0.06 | 0.67 (0.02) / 0.68 (0.02) | 0.58 / 0.53 | 0.52 / 0.42 |

What it says. (1) The white-noise bound (a true lower bound: convex, certified by the gap to
within 1-5 %) is 0.01-0.18x in every cell: vacuous. Without the drifting error the start's
posterior is already near 2 dB (paper seed 0: 20 s more of the best split of five-loop sweeps
and +-75-deg orbits), so no cell's time is bounded by the white information the candidates
carry; what stands between the start and 2 dB is the drifting error (one offset per link and
5-s block, 0.96-1.8 dB here), which only more *blocks* looking at each direction average out.
(2) With the drift (the posterior the ranking and the flights' spread use) the criterion is not
convex in the times (the blocks' sum enters as ``S W S``), the design found is a local one and
not a bound: in four cells it is slower than the greedy plan the same model predicts (paper
seed 1 1.11/0.89x against 0.81/0.74x, its gap 0.23/0.09 not closed in 80 steps; ground seed 2
0.67/0.68x against 0.58/0.53x). Where it did converge (gap <= 0.04: paper seed 0 optimized,
paper seed 2, ground seeds 0-1) it predicts 0.53-0.77x, 0.16-0.42 below the greedy's predicted
ratio but for paper seed 2 suggested (0.77 against 0.76): the sequencing loses time *in
prediction*. (3) But the flown times are not the predicted ones: every
greedy flight flew faster than its own model predicted (paper seed 0 0.90 -> 0.63x, seed 1
0.81 -> 0.59x, seed 2 0.76 -> 0.65x; ground 0.58-1.13 -> 0.42-0.80x), and on ground seeds 1-2
the flown greedy beat the predicted optimal design (0.58 against 0.70; 0.42 against 0.68). So the predicted model
cannot decide whether 0.6x is reachable: the question (A) asks is answered only for the white
part (yes, by far) and, with the drift, only in prediction (paper seed 0 suggested: the best
split found needs 0.78x, above 0.55, so in the model's terms no ranking of those candidates
reaches 0.6x there, if that local design is near the best; ground seed 0 suggested 0.53x:
reachable in the model, the greedy loses it).
The design spends its time on the loop sweeps (five loops, one or both drones turning) and on
orbits at +-45..75 deg with the anchor turning (paper), on 2-lap orbits at +15..+45 deg, ground
passes and the descent with a turn (ground), 7-30 s of each, usually less than the manoeuvre's
own duration: the relaxation flies manoeuvres in part, which a plan of whole manoeuvres cannot.

(B) Rankings that look at the end (time ratio flown, suggested / optimized; ``--draws 0``):

| cell | rate (default) | ``--design end`` | ``--design support`` |
| --- | --- | --- | --- |
| ground 0 | 0.68 / 0.58 | 0.82 / 0.71 | 0.68 / 0.58 |
| ground 1 | 0.80 / 0.58 | 1.23 / 0.87 | 0.80 / 0.58 |
| ground 2 | 0.52 / 0.42 | (stopped: lost on 0-1) | 0.45 / 0.42 |

``end`` ranks by the criterion's reduction per second at the anticipated final posterior (the
current one plus the optimal remaining design): the Frank-Wolfe direction of the whole problem.
At the design's optimum every candidate it uses has the same gradient, so the order among them
falls to their lengths and leads, and it chose long 2-lap orbits flown whole (ground seed 1:
a 49-s orbit, predicted 2.60 -> 2.34 dB) where the design wanted 7-17 s of each; it also
predicted worse plans (ground seed 0 1.07/1.27x against the rate's 0.83/0.80x) and cost one
design per step (30 steps, 20-60 s on ground under load, several minutes on paper). ``support``
(the rate ranking among the candidates the remaining design flies for the largest share of
their length, first) chose the same manoeuvres as the rate ranking on ground seeds 0-1 and on
the optimized plan of seed 2, and a faster suggested flight on seed 2 (0.52 -> 0.45x: two 12-s
climbs and descents with a turn, then orbits at +30 and +45 deg; single-draw error 1.50 dB against
the reference's 1.51). ``end`` is worse on the tuning seeds; ``support`` is better in one ground
cell of six and was not flown on paper (one design per ranking step, several minutes each there,
made a paper flight too long for the session), so neither is the default. On the held-out
ground seeds ``support`` flew 0.58 / 0.94x (seed 3; default 0.58 / 0.98x) and 3.00 / 0.50x
(the degenerate seed 4, as the default).
``ManoeuvreOptions(design="end")`` or ``"support"`` give them.

**The suggested flight's start as long as live needs** (:func:`live_start_s`; seeds 0-4, one
thread, 5 draws, load 1-7 on 2 cores). Every section above was measured with a 10-s start: the
reference's first unit for 10 s before the first ranking, an arbitrary choice (the ranking takes
its noise, smoothing and drift from the complete reference flight, not from the start). ``rplearn
live`` ranks after its first refit, which ``--order auto`` makes once it has SH-2's samples (80
for two antennas, about 0.5 s of these radios) at its refit cadence (``--refit-s``, 2 s):
replaying the benchmark's own start flight through ``replay_session`` with ``live_advisor``
(paper and ground, seeds 0-1) gave the first refit and ranking at 2 s of log time on all four.
The start is therefore 2 s (computed by :func:`live_start_s` from the same rule); the ranking's
computing time (first ranking: 10-15 s on paper, 1-3 s on ground, one thread, load 5) is not
counted, as for no later step. What live ranks first is weaker than what this benchmark ranks
from: its first fit (about 300 samples) sat at an end of the smoothing grid (ground seed 0: SH-2
at the largest smoothing, every candidate's predicted spread 0.0002 dB, below the
``--until-spread`` floor, so all 39 score alike; paper seed 0: no smoothing, 17 dB), and a
session with ``--until-spread 2`` alone ended at that first refit (paper and ground seed 0: the
spread over the covered 1-2 % of the sphere 0.4-0.95 dB; since then ``--until-spread`` reads the
spread over the sphere, over the covered directions only with a coverage target, and a fit at
the largest smoothing gives no spread: :mod:`rplearn.workflows.live`). Time ratio and
expected-error difference (plan minus reference,
dB; ``*``: a check missed; the "10 s" column is the "whole" column above, its seeds 0-4 times
flown again with ``--draws 0`` in this state and repeated figure for figure):

| cell | 10-s start (before) | 2-s start (live's) |
| --- | --- | --- |
| paper 0 suggested / optimized | 0.63* / +0.41, 0.60 / +0.53* | 0.66* / +0.24, 0.60 / +0.53* |
| paper 1 suggested / optimized | 0.59 / -0.17, 0.52 / -0.03 | 0.56 / +0.10, 0.51 / +0.02 |
| paper 2 suggested / optimized | 0.65* / -0.27, 0.60 / -0.19 | 0.65* / +0.09, 0.60 / -0.19 |
| ground 0 suggested / optimized | 0.68* / +0.24, 0.58 / +0.32 | 0.56 / +0.42 (tol 0.43), 0.58 / +0.32 |
| ground 1 suggested / optimized | 0.80* / -0.30, 0.58 / -0.04 | 0.56 / -0.04, 0.58 / -0.04 |
| ground 2 suggested / optimized | 0.52 / -0.04, 0.42 / +0.02 | 0.72* / +0.09, 0.42 / +0.02 |
| both checks, seeds 0-2 | 7 of 12 | 8 of 12 |
| mean suggested time ratio paper / ground | 0.62 / 0.67 | 0.62 / 0.61 |
| paper 3 suggested / optimized | 0.62* / +0.38*, 0.58 / +0.31* | 0.58 / +0.39* (tol 0.28), 0.62* / +0.27* |
| paper 4 suggested / optimized | 0.56 / -0.18, 0.55 / +0.69 | 0.60 / +0.79* (tol 0.50), 0.55 / +0.69 |
| ground 3 suggested / optimized | 0.58 / -0.01, 0.98* / +0.12 | 0.97* / +0.37*, 0.98* / +0.12 |
| ground 4 suggested / optimized | 3.00* / -0.18, 0.50 / +0.35* | 1.00* / +0.16, 0.50 / +0.35* |
| both checks, seeds 3-4 | 3 of 8 | 1 of 8 |

The 8 s saved are not what moved the suggested cells: started from 2 s of data, the ranking
took another path in every suggested cell, from its first or second manoeuvre on (ground seed 2
from its fourth; ground seed 0 a 12-s climb, a descent and a 38-s orbit where it flew two climbs
and a 46-s orbit; paper seeds 0-2 another first manoeuvre), and the times moved by -14 to +39 s (seeds 0-2: ground 77 ->
63 s, 46 -> 33 s, 102 -> 141 s; paper 140 -> 148 s, 191 -> 183 s, 146 -> 146 s; held out: ground
seed 3 32 -> 54 s, a 40-s orbit; paper seed 4 stops at 0.60x with its expected worst error
0.79 dB above the reference's). As with the variants above, the cells pass or miss by which
near-tied candidates come first; the suggested flights' mean ratio on paper is unchanged (0.62),
on ground it fell from 0.67 to 0.61x. Ground seed 4's
reference reaches 2 dB at 4 s: the suggested flight at its first manoeuvre's first 2-s step (4 s,
1.00x; 12 s, 3.00x, with the 10-s start), the optimized plan at its first (2 s, 0.50x). The
optimized plans do not depend on the start; their figures moved only where the suggested flight
flew another number of manoeuvres, which reseeds the units flown after it (paper 3 optimized
0.58 -> 0.62x, the same plan: a single cell's ratio moves by 0.04 with its noise alone). With the
start as long as live needs, item 3 holds in 8 of 12 tuning cells and 1 of 8 held-out: not met.

**Each plan seeded on its own, and the ranking live makes** (session 46; seeds 0-4, one thread,
``--draws 0``, load about 4 on 2 cores). The first draw flew the plans one after another from one
seed counter, so the optimized flight's noise followed the number of manoeuvres the suggested
flight flew (ground seed 1: the same optimized plan 0.58x in one run, 0.72x in another); each plan
now starts at its own offset (``PLAN_SEED``), as the other draws did. Time ratios to 2 dB (the
single-draw error check is a coin flip at this tolerance, see above, and is not tabulated):

| planner | ground 0 | 1 | 2 | 3 | 4 | paper 0 | 1 | 2 | 3 | 4 | <= 0.6x |
| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |
| suggested (reference posterior, default) | 0.54 | 0.91 | 0.53 | 0.72 | 1.00 | 0.67 | 0.54 | 0.64 | 0.58 | 0.59 | 5 of 10 |
| suggested as ``live`` ranks (``--ranker live``) | 0.64 | 0.88 | 0.68 | 0.91 | 1.00 | 1.01 | 0.51 | 1.02 | 0.80 | 0.54 | 2 of 10 |
| optimized (``trajectory --optimize``) | 0.58 | 0.58 | 0.41 | 0.94 | 0.50 | 0.60 | 0.53 | 0.62 | 0.59 | 0.57 | 8 of 10 |

The default suggested flight ranks from the posterior learned on the *complete* reference flight
(its noise, inflation, smoothing and drift), which ``rplearn live`` cannot know at the start.
``--ranker live`` ranks as the session does: :class:`~rplearn.models.live_stats.LiveStatistics`
(``--order auto``, accumulated at SH-15 with their time blocks), its refit of the flight so far,
and :func:`rplearn.workflows.live_advice.ranking_options` (the refit's smoothing, its noise times
the square root of its variance inflation, the drift estimated from the session's blocks, each
node's sphere as the target). Measuring it found three faults of live's advice, fixed: (1) the
first refits (ground, 2 s: SH-2 at the largest smoothing) claimed patterns known to 0.0003 dB, and
every candidate scored alike; such a fit is now ranked under the nominal 6-dB smoothness prior of
``trajectory --optimize``; (2) the ranking read its posterior with the fit's bare noise (ground
seed 0: 4.26 dB where the fit's covariance says 11.05), so it predicted 1.0-1.9 dB where the flight
stood at 2.0-2.9 dB; (3) once every node was below the floor (``--until-spread``) in the ranking's
posterior, no candidate was rewarded and the same yaw turn was ranked first 14 times (paper seed 3:
1.72x before the fix, 0.80x after). What remains: live's early posteriors are far from the complete
flight's (the smoothing chosen from 2-20 s of flight jumps between 0 and the cap; the drift
estimated from a few 5-s blocks), so its first suggestions differ (paper seeds 0 and 2: the whole
248-255-s paper unit first, flown to the target at 1.01-1.02x); ranked as live ranks, item 3 holds
in 2 of 10 cells, against 5 of 10 for the default's oracle posterior. Ground seed 4's reference
reaches 2 dB at 4 s, before any plan's first 2-s step could end below 0.6x of it.

**Live ranking with an earlier flight's model** (``--ranker live --hyper previous``: the earlier
flight's model file, seed :data:`PREVIOUS_SEED`, read by
:func:`rplearn.workflows.live_advice.earlier_fit` as ``rplearn live --from-model`` reads it;
its noise, smoothing and drift rank while the session has learned fewer samples than that fit,
29,963 on ``ground`` and 111,991 on ``paper``, so throughout these flights). Seeds 0-4,
``--draws 0 --planners suggested``, one thread, two runs at a time on an otherwise idle 2-core
machine, live's own ranking (``--ranker live``) measured again on the same code:

| ranking | ground 0 | 1 | 2 | 3 | 4 | paper 0 | 1 | 2 | 3 | 4 | <= 0.6x |
| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |
| live, its own refits (``--ranker live``) | 0.64 | 0.88 | 0.68 | 0.91 | 1.00 | 1.01 | 0.74 | 1.02 | 0.80 | 0.54 | 1 of 10 |
| live ``--from-model`` (``--hyper previous``) | 0.78 | 0.66 | 0.61 | 0.69 | 1.00 | 0.64 | 0.49 | 0.58 | 0.51 | 0.55 | 4 of 10 |
| the same, the benchmark's targets (``live-targets``) | 0.56 | 0.91 | 0.52 | 0.97 | 1.00 | | | | | | |

On ``paper`` the earlier model's figures remove the first suggestion that cost most (seeds 0
and 2: the whole 255-s paper unit first, 1.01-1.02x) and the mean ratio falls from 0.82 to
0.55x; on ``ground`` it falls from 0.82 to 0.75x (seed 4's degenerate 1.00x included), better on
seeds 1-3 and worse on seed 0 (0.64 -> 0.78x), and no cell reaches 0.6x: live ranks for each
node's whole sphere, while the benchmark's targets on ``ground`` are the few percent of it the
reference flight saw (ranked for those, ``live-targets``, seeds 0 and 2 pass, 1 and 3 do not).
Item 3 is still not met as the live session ranks: 4 of 10 cells.

Criteria per preset and seed: time to 2 dB of suggested and of optimized <= 60 % of the
reference's, and their expected worst per-node pattern error no worse than the reference's as
above (``--draws 0``: the single-draw check with +0.05 dB, as before).

Usage: ``python benchmarks/manoeuvres.py [--presets paper,ground] [--seeds 0,1,2] [--posterior honest|inflated]
[--correlated reference|own|off] [--prior-std 0] [--draws 5] [--yaw-rate 45] [--arcs] [--tilt] [--no-sweeps]
[--rate information|spread] [--prefixes 4] [--lookahead 4] [--aimed 3] [--design rate|end|support] [--bound yes|only] [--tiny]``
(``--tiny``: the ``smoke`` preset at SH-4 with ``--budget``, at most 2 draws and fewer candidates (``TINY_CANDIDATES``),
a few seconds; its criteria are printed, not enforced).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pandas as pd

# one BLAS thread: the ranking's near-ties otherwise fall by the last bits of the statistics, which
# the thread policy changes with the machine's load, and a run cannot be repeated figure for figure
os.environ.setdefault("RPLEARN_THREADS", "1")

from rplearn.analysis.manoeuvre_bound import design_bound
from rplearn.analysis.manoeuvre_cells import DirectionCells
from rplearn.analysis.manoeuvre_prior import NOMINAL_PRIOR_STD_DB
from rplearn.analysis.manoeuvres import (
    ManoeuvreOptions,
    correlated_error_std_db,
    greedy_plan,
    pattern_spreads,
    prior_penalty_weight,
    rank_manoeuvres,
    steady_tilt_accel,
)
from rplearn.analysis.pattern_error import pattern_errors_db
from rplearn.core.bases import fibonacci_grid_nodes
from rplearn.core.coverage import nearest_angle_deg
from rplearn.core.gauge import EQUAL_MEAN
from rplearn.core.lsq.block_sums import DEFAULT_BLOCK_S, BlockSums
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.penalty import penalty_vector
from rplearn.core.lsq.solver import solve
from rplearn.data.sync import SyncOptions, synchronise
from rplearn.data.tables import link_samples
from rplearn.models.auto import SAMPLES_PER_COEF
from rplearn.models.live_stats import LiveStatistics
from rplearn.models.options import FitOptions
from rplearn.models.own_posterior import OwnPrior, own_pattern_posterior
from rplearn.models.patterns import PatternSet
from rplearn.models.spec import ModelSpec
from rplearn.plan.campaign import Campaign
from rplearn.plan.manoeuvres import CandidateOptions
from rplearn.sim import simulate
from rplearn.sim.presets import make_preset
from rplearn.workflows.calibration_plan import DEFAULT_NOISE_STD_DB, options_from_model
from rplearn.workflows.live import LiveOptions
from rplearn.workflows.live_advice import EarlierFit, earlier_fit, ranking_options

TARGET_DB = 2.0
TIME_RATIO = 0.6
STEP_S = 2.0
#: ``rplearn live``'s refit cadence [s] (``--refit-s``'s default): its first suggestion is ranked
#: after its first refit, which a replay of the logs (:func:`rplearn.workflows.live.replay_session`)
#: makes at the first multiple of it in log time at which ``--order auto`` has SH-2's samples.
LIVE_REFIT_S = LiveOptions().refit_s


def live_start_s(t_in: np.ndarray, n_nodes: int) -> float:
    """The flight time at which ``rplearn live`` has its first suggestion on a flight whose samples
    arrive at ``t_in`` [s]: its first refit, at the first multiple of :data:`LIVE_REFIT_S` with at
    least the samples :func:`rplearn.models.auto.auto_orders` needs for SH-2 (``n_nodes * 4 *
    SAMPLES_PER_COEF``, reached after about 0.5 s here). Measured by replaying the start's logs
    (the benchmark's own start flight, seeds 0-1 of ``paper`` and ``ground``) through
    :func:`rplearn.workflows.live.replay_session` with the CLI's ``live_advisor`` (``--order auto``,
    ``--refit-s 2``, ranking after every refit): the first refit and its ranking at 2 s of log
    time, 296-307 samples learned, on all four. The ranking's own computing time is not counted
    (nor for any later step of the suggested flight): one thread, load about 5 on 2 cores, the
    first ranking took 10-15 s on ``paper`` (321 candidates) and 1-3 s on ``ground`` (39), during
    which a real flight flies on. ``run_live`` refits at the first poll with the samples once
    ``--refit-s`` has passed since the session started (usually before the data), so its first
    refit can come before 2 s of data; its ranking then still takes the time above."""
    need = n_nodes * 4 * SAMPLES_PER_COEF
    t = np.sort(np.asarray(t_in, np.float64))
    if t.size < need:
        raise ValueError(f"the start flight has {t.size} samples, fewer than the {need} live's first refit needs")
    return float(LIVE_REFIT_S * max(1, np.ceil(t[need - 1] / LIVE_REFIT_S)))
PRIOR_STD_DB = 6.0
#: Independent noise draws of every flight plan for the expected error (``--draws``).
DRAWS = 5
#: "No worse" in expectation: the plan's mean worst error at most the reference's plus this many
#: standard errors of the difference of the two means.
ERROR_SE = 2.0
#: Seed step between draws (a draw's flights are seeded ``seed * 1000 + PLAN_SEED * plan + k + DRAW_SEED * draw``;
#: the plan 0 for the reference, 1 for the suggested flight, 2 for the optimized one; draw 0 too).
DRAW_SEED = 100_000
#: Seed step between the plans of a draw (a plan flies fewer units than this).
PLAN_SEED = 300
FIXED = {"ground": ("G",)}
#: Where the planners' hyper-parameters come from (``--hyper``; the module docstring's "What the planners know").
HYPERS = ("reference", "previous", "cli", "flags")
#: The seed of the earlier flight of the same antennas whose fit ``--hyper previous`` plans with.
PREVIOUS_SEED = 7919


def _subset(samples: Any, m: np.ndarray) -> Any:
    """The samples ``m`` selects (a :class:`~rplearn.data.tables.LinkSamples` of them)."""
    d = samples.directions

    def cut(a: Any) -> Any:
        return None if a is None else np.asarray(a)[m]

    return replace(samples, directions=type(d)(d.az_tx[m], d.el_tx[m], d.az_rx[m], d.el_rx[m]), tx_index=samples.tx_index[m],
                   rx_index=samples.rx_index[m], joint_gain_db=samples.joint_gain_db[m], distance_m=samples.distance_m[m],
                   frequency_hz=cut(samples.frequency_hz), tx_z_m=cut(samples.tx_z_m), rx_z_m=cut(samples.rx_z_m),
                   t_s=cut(samples.t_s))


class LiveRanker:
    """The ranking ``rplearn live`` makes (``--ranker live``): its statistics
    (:class:`~rplearn.models.live_stats.LiveStatistics`, ``--order auto``, accumulated at the largest
    candidate order with their 5-s time blocks), its refit from them, and the posterior its advisor
    ranks with (:func:`rplearn.workflows.live_advice.ranking_options`: the refit's smoothing and
    noise, the nominal prior while the refit is at the largest smoothing, the drift estimated from
    the session's blocks). The candidates, the packet rate and the target directions are the
    benchmark's (``options``); the target directions live's (each node's sphere), or with
    ``sphere=False`` the benchmark's. ``earlier`` (``--hyper previous``): the earlier flight's model
    file read as ``rplearn live --from-model`` reads it (:func:`rplearn.workflows.live_advice.earlier_fit`),
    ranked with while the session has learned fewer samples than that fit."""

    def __init__(self, nodes: tuple[str, ...], options: ManoeuvreOptions, sphere: bool = True) -> None:
        self.nodes = nodes
        self.earlier: EarlierFit | None = None
        self.stats = LiveStatistics(ModelSpec.parse("sh"), nodes, FitOptions(auto=True))
        self.options = replace(options, penalty_weight=None, correlated_std_db=None, misfit_std_db=0.0,
                               prior_variance_factor=1.0, targets=None if sphere else options.targets)

    def add(self, samples: Any, m: np.ndarray, t_s: np.ndarray) -> None:
        """Learn the samples ``m`` selects, flown at flight times ``t_s`` (one per selected sample)."""
        self.stats.add(pd.DataFrame({"t": np.asarray(t_s, np.float64)}), _subset(samples, m))

    def best(self, poses: Any) -> Any:
        """The manoeuvre live ranks first from the latest ``poses``."""
        fitted = self.stats.refit()
        total = self.stats.total()
        opts = ranking_options(self.options, total, fitted, self.earlier)
        return rank_manoeuvres(total, fitted.spec, list(self.nodes), poses, opts, total.blocks)[0]


@dataclass
class Flight:
    """The accumulated statistics of a flight and where it first reached the target spread."""

    name: str
    normal: NormalEquations
    blocks: BlockSums | None = None
    cells: DirectionCells | None = None
    t_s: float = 0.0
    history: list[tuple[float, float]] = field(default_factory=list)
    reached_s: float | None = None
    error_db: dict[str, float] = field(default_factory=dict)
    spread_db: dict[str, float] = field(default_factory=dict)
    own_db: dict[str, float] = field(default_factory=dict)
    steps: list[str] = field(default_factory=list)
    adds: list[tuple[Any, np.ndarray]] = field(default_factory=list)
    budget_db: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    plan: list[tuple[tuple[Any, ...], float, float | None]] = field(default_factory=list)
    draws_db: list[float] = field(default_factory=list)
    draw_spreads_db: list[float] = field(default_factory=list)
    live: LiveRanker | None = None

    def expected(self) -> tuple[float, float]:
        """Mean worst per-node error over the independent draws and its standard error [dB]."""
        v = np.asarray(self.draws_db, np.float64)
        if v.size == 0:
            return float("nan"), float("nan")
        return float(v.mean()), (float(v.std(ddof=1) / np.sqrt(v.size)) if v.size > 1 else float("nan"))


@dataclass
class Setup:
    preset: str
    config: Any
    spec: ModelSpec
    nodes: tuple[str, ...]
    options: ManoeuvreOptions
    weight: float
    truth: Any = None
    seed: int = 0
    flown: int = 0
    correlated: str = "reference"
    block_s: float = DEFAULT_BLOCK_S
    budget: bool = False
    truths: dict[int, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    draw: int = 0

    def flight(self, name: str) -> Flight:
        basis = self.spec.basis()
        blocks = None if self.correlated == "off" else BlockSums(len(self.nodes), basis.n_coef, self.block_s)
        cells = DirectionCells(basis, len(self.nodes)) if self.options.misfit_std_db > 0 else None
        return Flight(name, NormalEquations(basis, len(self.nodes)), blocks, cells)


def _config(preset: str) -> Any:
    c = make_preset(preset)
    return replace(c, radio=replace(c.radio, link_offsets_db=(), dropouts=0, unit_level_std_db=0.0))


def fly(setup: Setup, units: tuple[Any, ...]) -> tuple[list[Any], Any]:
    """Simulate units one after the other; per unit its samples with their time in it, and the pose log."""
    setup.flown += 1
    seed = setup.seed * 1000 + setup.flown + DRAW_SEED * setup.draw
    sim = simulate(replace(setup.config, campaign=Campaign(units, gap_s=10.0)), seed=seed)
    setup.truth = sim.ground_truth
    ds = synchronise(sim.pose_log, sim.signal_log, SyncOptions()).dataset
    starts = dict(zip([u.label for u in units], sim.config.campaign.start_times_s()))
    out = []
    for u in units:
        part = ds[ds["unit"] == u.label]
        samples = link_samples(part, nodes=setup.nodes)
        if setup.budget:
            setup.truths[id(samples)] = _truth_gains(sim, part, samples, setup.nodes)
        out.append((samples, part["t"].to_numpy() - starts[u.label], u.duration_s))
    return out, sim.pose_log


def _joint_truth(truth: Any, samples: Any) -> np.ndarray:
    out = np.zeros(samples.tx_index.size)
    d = samples.directions
    for a, na in enumerate(samples.nodes):
        for b, nb in enumerate(samples.nodes):
            m = (samples.tx_index == a) & (samples.rx_index == b)
            if np.any(m):
                out[m] = truth.predict_joint_gain_db(na, nb, d.az_tx[m], d.el_tx[m], d.az_rx[m], d.el_rx[m])
    return out


def _truth_gains(sim: Any, part: Any, samples: Any, nodes: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    """The true joint gain at the logged (estimated) directions and at the true ones, per sample."""
    keys = part[["t", "tx", "rx"]].astype({"tx": str, "rx": str})
    true = sim.matched_truth.drop(columns=["unit"]).astype({"tx": str, "rx": str})
    true = keys.merge(true, on=["t", "tx", "rx"], how="left")
    true["rssi_dbm"] = part["rssi_dbm"].to_numpy()
    return _joint_truth(sim.ground_truth, samples), _joint_truth(sim.ground_truth, link_samples(true, nodes=nodes))


def _fitted(setup: Setup, normal: NormalEquations) -> PatternSet:
    basis = setup.spec.basis()
    pen = penalty_vector(basis, len(setup.nodes), setup.weight, 1.0, setup.options.power)
    sol = solve(normal, list(setup.nodes), ridge=setup.spec.ridge_weight, gauge=EQUAL_MEAN, penalty=pen)
    return PatternSet(basis=basis, nodes=setup.nodes, coef=sol.coef, gauge=[g.to_dict() for g in sol.report.gauges])


def _budget(setup: Setup, flight: Flight) -> None:
    """The pattern error split by its source: the same fit of the truth at the logged directions
    (bias: smoothing, aliasing, truncation), of the truth at the true directions less that
    (pointing: the pose estimates' errors), and of the rest (fading, rounding)."""
    fits = []
    for which in range(3):
        normal = NormalEquations(setup.spec.basis(), len(setup.nodes))
        for samples, m in flight.adds:
            logged, true = setup.truths[id(samples)]
            y = (logged, true - logged, samples.joint_gain_db - true)[which]
            d = samples.directions
            normal.add(type(d)(d.az_tx[m], d.el_tx[m], d.az_rx[m], d.el_rx[m]), samples.tx_index[m], samples.rx_index[m], y[m])
        fits.append(_fitted(setup, normal))
    for node, (az, el) in (setup.options.targets or {}).items():
        parts = [fits[0].evaluate(node, az, el) - setup.truth.evaluate(node, az, el), fits[1].evaluate(node, az, el),
                 fits[2].evaluate(node, az, el)]
        flight.budget_db[node] = tuple(float(np.sqrt(np.mean((v - v.mean()) ** 2))) for v in parts)  # type: ignore[assignment]


def _fit_error(setup: Setup, flight: Flight) -> None:
    basis = setup.spec.basis()
    model = _fitted(setup, flight.normal)
    flight.error_db = pattern_errors_db(model, setup.truth, setup.options.targets or {}, remove_constant=True)
    if setup.budget:
        _budget(setup, flight)
    small = ModelSpec("sh", 2).basis()
    own = own_pattern_posterior(flight.normal, small, setup.nodes,
                                OwnPrior(setup.weight, 1.0, setup.options.power, setup.spec.ridge_weight, EQUAL_MEAN, None),
                                setup.options.noise_std_db**2, None)
    if own is not None:
        p = basis.n_coef
        from rplearn.analysis.manoeuvres import target_metrics

        metrics = target_metrics(basis, setup.nodes, setup.options)
        flight.own_db = {n: float(np.sqrt(max(np.sum(m * own.covariance[k * p:(k + 1) * p, k * p:(k + 1) * p]), 0.0)))
                         for k, (n, m) in enumerate(zip(setup.nodes, metrics))}


def accumulate(setup: Setup, flight: Flight, parts: list[Any], lead_s: float = 0.0, until_s: float | None = None,
               stop: bool = True, cut_s: float | None = None) -> None:
    """Add each unit's samples in steps of STEP_S flight time; stop at the first 2 dB (``cut_s``:
    at that flight time instead, the spread then read once)."""
    flight.t_s += lead_s
    for samples, t_in, dur in parts:
        end = dur if until_s is None else min(dur, until_s)
        edges = np.arange(0.0, end + STEP_S, STEP_S)
        edges[-1] = end
        for a, b in zip(edges[:-1], edges[1:]):
            m = (t_in >= a) & ((t_in < b) if b < end else (t_in <= b))
            d = samples.directions
            if np.any(m):
                flight.normal.add(type(d)(d.az_tx[m], d.el_tx[m], d.az_rx[m], d.el_rx[m]), samples.tx_index[m],
                                  samples.rx_index[m], samples.joint_gain_db[m])
                if setup.budget:
                    flight.adds.append((samples, m))
                if flight.live is not None:
                    flight.live.add(samples, m, flight.t_s + t_in[m])
                if flight.blocks is not None:
                    flight.blocks.follow(flight.normal, flight.t_s + 0.5 * (a + b))
                if flight.cells is not None:
                    flight.cells.add(type(d)(d.az_tx[m], d.el_tx[m], d.az_rx[m], d.el_rx[m]), samples.tx_index[m],
                                     samples.rx_index[m])
            if cut_s is not None:
                if flight.t_s + b >= cut_s - 1e-9:
                    flight.reached_s = flight.t_s + b
                    flight.spread_db = pattern_spreads(flight.normal, setup.spec, setup.nodes, setup.options, flight.blocks,
                                                       flight.cells)
                    flight.error_db = pattern_errors_db(_fitted(setup, flight.normal), setup.truth, setup.options.targets or {},
                                                        remove_constant=True)
                    return
                continue
            if stop is False:
                continue
            spreads = pattern_spreads(flight.normal, setup.spec, setup.nodes, setup.options, flight.blocks, flight.cells)
            flight.history.append((flight.t_s + b, max(spreads.values())))
            if flight.reached_s is None and max(spreads.values()) <= TARGET_DB:
                flight.reached_s = flight.t_s + b
                flight.spread_db = spreads
                _fit_error(setup, flight)
                return
        flight.t_s += end


def _targets(setup: Setup, parts: list[Any]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    az, el = fibonacci_grid_nodes(1024)
    out = {}
    for k, node in enumerate(setup.nodes):
        saz, sel = [], []
        for samples, _, _ in parts:
            d = samples.directions
            saz += [d.az_tx[samples.tx_index == k], d.az_rx[samples.rx_index == k]]
            sel += [d.el_tx[samples.tx_index == k], d.el_rx[samples.rx_index == k]]
        near = nearest_angle_deg(az, el, np.concatenate(saz), np.concatenate(sel))
        out[node] = (az[near <= 10.0], el[near <= 10.0])
    return out


def _learned_prior(parts: list[Any], nodes: tuple[str, ...], power: float, honest: bool = True) -> tuple[float, float, float, float]:
    """The smoothing ``fit --degree auto`` chooses on the complete reference flight (its units' own
    folds), as an absolute weight (times the penalty's scale at the chosen order, as
    :mod:`rplearn.models.own_posterior` continues it), the fit's noise and its held-out misfit per
    node; ``honest=False``: the noise times the variance inflation and no misfit (the benchmark
    before the misfit term)."""
    from rplearn.core.lsq.penalty import penalty_scale
    from rplearn.models.auto import fit_auto

    units = {f"u{k}": samples for k, (samples, _, _) in enumerate(parts)}
    fitted, _ = fit_auto(units, power=power)
    model = fitted.model if hasattr(fitted, "model") else fitted
    training = model.training
    chosen = NormalEquations(model.basis, len(nodes))
    for samples, _, _ in parts:
        chosen.add(samples.directions, samples.tx_index, samples.rx_index, samples.joint_gain_db)
    scale = penalty_scale(chosen.gram, chosen.n_pattern_columns)
    smoothing = float(training.smoothing if hasattr(training, "smoothing") else training["smoothing"])
    inflation = float(training.variance_inflation or 1.0)
    misfit = float(training.misfit_std_db or 0.0)
    noise = float(training.noise_std_db) * (1.0 if honest else float(np.sqrt(inflation)))
    print(f"  learned prior: {model.basis.label}, smoothing {smoothing:.3g} x scale {scale:.3g}, noise {training.noise_std_db:.2f} dB "
          f"(variance inflation {inflation:.2f}), held-out misfit {misfit:.2f} dB per node; the posterior's noise {noise:.2f} dB"
          + (f", prior variance x{inflation:.2f}, misfit {misfit:.2f} dB per direction cell" if honest else ""))
    return smoothing * scale, noise, (misfit if honest else 0.0), (inflation if honest else 1.0)


def _reference_drift(setup: Setup, parts: list[Any]) -> float:
    """The drifting error's spread the complete reference flight shows [dB]."""
    whole = setup.flight("whole")
    accumulate(setup, whole, parts, stop=False)
    assert whole.blocks is not None
    return correlated_error_std_db(whole.normal, setup.spec, whole.blocks, setup.options)


def _learned(setup: Setup, parts: list[Any], prior_std_db: float, posterior: str, source: str) -> dict[str, Any]:
    """The hyper-parameters a fit of the flight ``parts`` gives, as :class:`ManoeuvreOptions` fields:
    with ``prior_std_db <= 0`` the prior, noise, misfit and variance inflation ``fit --degree auto``
    learns (:func:`_learned_prior`), and with ``--correlated reference`` the drifting error's size
    its blocks show (:func:`_reference_drift`, under that prior and noise)."""
    out: dict[str, Any] = {}
    if prior_std_db <= 0:
        print(f"  from {source}:")
        weight, noise, misfit, inflation = _learned_prior(parts, setup.nodes, setup.options.power, posterior == "honest")
        out = {"penalty_weight": weight, "noise_std_db": noise, "misfit_std_db": misfit, "prior_variance_factor": max(inflation, 1.0)}
    if setup.correlated == "reference":
        there = replace(setup, options=replace(setup.options, **out), weight=float(out.get("penalty_weight", setup.weight)))
        out["correlated_std_db"] = drift = _reference_drift(there, parts)
        print(f"  drifting error from {source} ({setup.block_s:g}-s blocks): {drift:.3f} dB per block")
    return out


def _planning_options(setup: Setup, hyper: str, stated: ManoeuvreOptions, learning: tuple[Any, ...], prior_std_db: float,
                      posterior: str) -> tuple[ManoeuvreOptions, EarlierFit | None]:
    """The options the planners (the suggested flight's ranking and the optimized plan) are given
    (the module docstring's table "What the planners know"): ``setup.options`` with the noise,
    prior and drift of ``hyper``. ``stated``: the options before any fit (the stated prior and the
    simulator's nominal noise). ``previous`` and ``flags`` fit the earlier flight as ``rplearn fit
    --order auto`` does, write its model file and read it back through
    :func:`rplearn.workflows.calibration_plan.options_from_model`, the code of ``trajectory
    --optimize --from-model`` (``flags``: with ``--prior-std`` of the CLI's default; with
    ``--prior-std DB``, ``previous`` states it and the simulator's noise, the model giving the
    drift alone; ``--correlated off``: ``--drift 0``). The target directions, the candidates, the
    packet rate and the tilt stay ``setup.options``' (what the user wants to learn and what the
    radio and the vehicles do, not a fit's figures). With ``previous`` also the same model file as
    ``rplearn live --from-model`` reads it (:func:`rplearn.workflows.live_advice.earlier_fit`), for
    ``--ranker live``; else None."""
    judged = setup.options
    if hyper == "reference":
        return judged, None
    if hyper in ("previous", "flags"):
        earlier = replace(setup, seed=PREVIOUS_SEED, flown=0, draw=0, budget=False, truths={},
                          options=replace(stated, targets=judged.targets))
        parts, _ = fly(earlier, learning)
        stated_prior = NOMINAL_PRIOR_STD_DB if hyper == "flags" else (prior_std_db if prior_std_db > 0 else None)
        with tempfile.TemporaryDirectory() as folder:
            path = _earlier_model(parts, setup.options.power, os.path.join(folder, "previous.json"))
            opts = options_from_model(path, judged, setup.spec,
                                      noise_std_db=stated.noise_std_db if hyper == "previous" and prior_std_db > 0 else None,
                                      prior_std_db=stated_prior, drift_std_db=0.0 if setup.correlated == "off" else None)
            live_prior = earlier_fit(path, ModelSpec.parse("sh")) if hyper == "previous" else None
        print(f"  the planners' hyper-parameters from the earlier flight's model (seed {PREVIOUS_SEED}, through "
              f"options_from_model{', --prior-std ' + format(stated_prior, 'g') if stated_prior else ''}): noise "
              f"{opts.noise_std_db:.2f} dB, penalty weight {opts.penalty_weight:.3g}, drift {opts.correlated_std_db:.3f} dB")
        return opts, live_prior
    if hyper == "cli":
        noise = DEFAULT_NOISE_STD_DB
        weight = prior_penalty_weight(setup.spec.basis(), NOMINAL_PRIOR_STD_DB, noise, setup.spec.ridge_weight, judged.power)
        print(f"  the planners' hyper-parameters: the CLI's defaults (--noise {noise:.2f} dB, --prior-std "
              f"{NOMINAL_PRIOR_STD_DB:g} dB, --drift 0)")
        return replace(judged, noise_std_db=noise, penalty_weight=weight, misfit_std_db=0.0, prior_variance_factor=1.0,
                       correlated_std_db=0.0), None
    raise ValueError(f"hyper: expected one of {', '.join(HYPERS)}, got {hyper!r}")


def _earlier_model(parts: list[Any], power: float, path: str) -> str:
    """``rplearn fit --order auto`` of an earlier flight's units (their samples with their times),
    written to ``path``."""
    from rplearn.models.auto import fit_auto

    fitted, _ = fit_auto({f"u{k}": samples for k, (samples, _, _) in enumerate(parts)}, power=power)
    fitted.model.save(path)
    return path


def run(preset: str, order: int, seed: int, limit_s: float, power: float = 2.0, prior_std_db: float = PRIOR_STD_DB,
        correlated: str = "reference", block_s: float = DEFAULT_BLOCK_S, posterior: str = "inflated",
        budget: bool = False, draws: int = DRAWS, candidates: dict[str, Any] | None = None, tilt: bool = False,
        aggregate: str = "rms", rate: str = "spread", prefixes: int = ManoeuvreOptions().prefixes,
        lookahead: int = ManoeuvreOptions().lookahead, aimed: int = ManoeuvreOptions().aimed,
        design: str = ManoeuvreOptions().design, bound: str = "", ranker: str = "reference",
        hyper: str = "reference", planners: str = "both") -> dict[str, Flight]:
    config = _config(preset)
    learning = config.campaign.with_role("learning").units
    nodes = tuple(sorted(config.node_antennas))
    noise = float(np.sqrt(config.radio.fading_std_db**2 + (1.0 / 12.0 if config.radio.quantize else 0.0)))
    spec = ModelSpec("sh", order)
    weight = prior_penalty_weight(spec.basis(), prior_std_db, noise, spec.ridge_weight, power) if prior_std_db > 0 else 0.0
    speed = float(getattr(learning[0], "speed_m_s", 1.5))
    cands = CandidateOptions(fixed_nodes=FIXED.get(preset, ()), speed_m_s=speed, **(candidates or {}))
    opts = ManoeuvreOptions(noise_std_db=noise, packet_rate_hz=config.radio.packet_rate_hz * (1 - config.radio.loss_probability),
                            penalty_weight=weight, candidates=cands, power=power, correlation_s=block_s, aggregate=aggregate,
                            rate=rate, prefixes=prefixes, lookahead=lookahead, aimed=aimed, design=design)
    setup = Setup(preset, config, spec, nodes, opts, weight, seed=seed, correlated=correlated, block_s=block_s, budget=budget)
    stated = opts
    ref_parts, _ = fly(setup, learning)
    setup.options = replace(opts, targets=_targets(setup, ref_parts))
    # the error model every flight's spread is read under: the fit of the complete reference flight
    setup.options = opts = replace(setup.options, **_learned(setup, ref_parts, prior_std_db, posterior, "the reference flight"))
    setup.weight = float(opts.penalty_weight or 0.0)
    ref = setup.flight("reference")
    ref.plan = [(tuple(learning), 0.0, None)]
    accumulate(setup, ref, ref_parts)
    # suggested: the reference's first seconds until live's first suggestion, then the top-ranked manoeuvre, repeatedly
    sug = setup.flight("suggested")
    setup.flown = PLAN_SEED  # each plan's flights seeded from its own offset, as replay() seeds them
    if ranker.startswith("live"):
        sug.live = LiveRanker(nodes, replace(opts, floor_db=TARGET_DB), sphere=ranker == "live")
    start_parts, poses = fly(setup, (learning[0],))
    start_s = live_start_s(start_parts[0][1], len(nodes))
    print(f"  suggested flight's start: {start_s:g} s (live's first refit and suggestion)")
    accumulate(setup, sug, start_parts[:1], until_s=start_s)
    sug.plan = [((learning[0],), 0.0, start_s)]
    poses = poses[poses["t"] <= start_s]
    if tilt:  # the wind's drag the drones lean against, from the start's poses (both planners)
        accel = steady_tilt_accel(poses, FIXED.get(preset, ()))
        setup.options = opts = replace(opts, steady_accel_enu_m_s2=accel)
        print(f"  steady tilt from the start's poses: {np.degrees(np.arctan(np.hypot(accel[0], accel[1]) / 9.80665)):.1f} deg "
              f"({accel[0]:+.2f}, {accel[1]:+.2f}) m/s^2")
    opts, earlier = _planning_options(setup, hyper, stated, learning, prior_std_db, posterior)
    if sug.live is not None and earlier is not None:  # as rplearn live --from-model reads the earlier flight's model file
        sug.live.earlier = earlier
        print(f"  --ranker live --from-model: {earlier.text()}")
    first = learning[0].evaluate(np.array([0.0]))
    start = {n: (tuple(first.position_enu_m[0, j]), float(np.degrees(first.yaw_rad[0, j]))) for j, n in enumerate(learning[0].nodes)}
    if bound:
        _print_bound(setup, ref, sug, poses, start, limit_s)
        if bound == "only":
            return {"reference": ref}
    k = 0
    while sug.reached_s is None and sug.t_s < limit_s and planners != "optimized":
        if sug.live is not None:
            best = sug.live.best(poses)
        else:
            best = rank_manoeuvres(sug.normal, spec, nodes, poses, replace(opts, floor_db=TARGET_DB), sug.blocks, sug.cells)[0]
        k += 1
        unit = replace(best.candidate.unit, label=f"m{k:02d}")
        parts, poses = fly(setup, (unit,))
        sug.plan.append(((unit,), best.candidate.lead_s, None))
        accumulate(setup, sug, parts, lead_s=best.candidate.lead_s)
        flown = "" if not sug.history else f", flown {sug.history[-1][1]:.2f}"
        ahead = "" if best.time_to_target_s is None else f"; to {TARGET_DB:g} dB in {best.time_to_target_s:.0f} s"
        sug.steps.append(f"{best.name} ({best.duration_s:.0f} s; predicted {max(best.spread_before_db.values()):.2f} -> "
                         f"{max(best.spread_after_db.values()):.2f}{flown} dB{ahead})")
    # optimized: the greedy plan before the flight, from the reference's start poses
    plan = [] if planners == "suggested" else greedy_plan(NormalEquations(spec.basis(), len(nodes)), spec, nodes, start,
                                                          limit_s, TARGET_DB, opts)
    opt = setup.flight("optimized")
    setup.flown = 2 * PLAN_SEED  # not after however many manoeuvres the suggested flight flew
    opt.steps = [f"{s.manoeuvre.name} ({s.manoeuvre.duration_s:.0f} s)" for s in plan]
    for k, step in enumerate(plan):
        if opt.reached_s is not None:
            break
        unit = replace(step.manoeuvre.candidate.unit, label=f"p{k:02d}")
        parts, _ = fly(setup, (unit,))
        opt.plan.append(((unit,), step.manoeuvre.candidate.lead_s, None))
        accumulate(setup, opt, parts, lead_s=step.manoeuvre.candidate.lead_s)
    flights = {"reference": ref, "suggested": sug, "optimized": opt}
    if planners == "optimized":  # the suggested flight not flown (its start alone)
        del flights["suggested"]
    if planners == "suggested":  # the optimized plan not flown
        del flights["optimized"]
    for k, f in enumerate(flights.values()):
        for draw in range(1, draws + 1):
            replay(setup, f, draw, PLAN_SEED * k)
    return flights


def _bound_mode(args: argparse.Namespace) -> str:
    """What ``run`` does with the bound: ``--tiny`` prints it (its smoke test) unless ``--bound no``."""
    if args.bound == "no":
        return ""
    return "yes" if args.tiny and not args.bound else args.bound


def _print_bound(setup: Setup, ref: Flight, sug: Flight, poses: Any, start: dict[str, Any], limit_s: float) -> None:
    """(A): the optimal design's time to the target over the candidates offered after the
    suggested flight's start (and, for the optimized plan, from the prior at the start poses),
    white-noise (a bound) and with the drift (an estimate), as ratios to the reference's flown
    time, beside the greedy plan's predicted time from the same posterior (ranked by rate)."""
    spec, nodes, opts = setup.spec, setup.nodes, replace(setup.options, floor_db=TARGET_DB, design="rate")
    ref_s = ref.reached_s or float("nan")
    cases = (("suggested", sug.normal, sug.blocks, poses, sug.t_s), ("optimized", NormalEquations(spec.basis(), len(nodes)), None, start, 0.0))
    for name, normal, blocks, where, t0 in cases:
        t1 = time.perf_counter()
        plan = greedy_plan(normal, spec, nodes, where, limit_s, TARGET_DB, opts, blocks)
        reached = bool(plan) and max(plan[-1].spread_db.values()) <= TARGET_DB * (1 + 1e-9)
        greedy_s = t0 + plan[-1].end_s if reached else float("nan")
        t2 = time.perf_counter()
        out = {}
        for drift in (False, True):
            out[drift] = design_bound(normal, spec, nodes, where, TARGET_DB, opts, blocks, drift=drift)
        t3 = time.perf_counter()
        white, full = out[False].design, out[True].design
        print(f"  bound ({name}, from {t0:.0f} s, {len(out[False].names)} candidates; greedy {t2 - t1:.0f} s, designs "
              f"{t3 - t2:.0f} s): white-noise design {t0 + white.total_s:.0f} s = {(t0 + white.total_s) / ref_s:.2f}x "
              f"(gap {white.gap:.1e}; none below {t0 + white.certified_s:.0f} s = {(t0 + white.certified_s) / ref_s:.2f}x), "
              f"with the drift {t0 + full.total_s:.0f} s = {(t0 + full.total_s) / ref_s:.2f}x "
              f"(gap {full.gap:.1e}), greedy predicted {greedy_s:.0f} s = {greedy_s / ref_s:.2f}x of the reference's {ref_s:.0f} s")
        for label, b in (("white", out[False]), ("drift", out[True])):
            print(f"    {label} design: " + "; ".join(f"{n} {t:.0f} s" for n, t in b.support()[:10])
                  + f" ({len(b.support())} candidates of >= 0.5 s)")


def replay(setup: Setup, flight: Flight, draw: int, offset: int = 0) -> None:
    """Fly ``flight``'s plan again (the same commanded units, leads and cuts) under independent
    noise, fading, wind and pose errors (draw ``draw``; its flights seeded from ``offset``, one
    per plan, so that two plans flying the same unit first never share its noise), up to the
    flight time at which the first draw reached the target spread; its worst per-node error
    there joins ``flight.draws_db``."""
    if flight.reached_s is None:
        return
    flown, budget = setup.flown, setup.budget
    setup.flown, setup.draw, setup.budget = offset, draw, False
    try:
        again = setup.flight(flight.name)
        for units, lead_s, until_s in flight.plan:
            if again.reached_s is not None:
                break
            parts, _ = fly(setup, units)
            accumulate(setup, again, parts[:1] if until_s is not None else parts, lead_s=lead_s, until_s=until_s,
                       cut_s=flight.reached_s)
    finally:
        setup.flown, setup.draw, setup.budget = flown, 0, budget
    if again.error_db:
        flight.draws_db.append(max(again.error_db.values()))
        flight.draw_spreads_db.append(max(again.spread_db.values()))


def expected_no_worse(flight: Flight, ref: Flight) -> tuple[bool, float, float]:
    """Whether the plan's expected worst error is no worse than the reference's: the difference of
    the two means over their independent draws, and the tolerance ``ERROR_SE`` standard errors of
    that difference (``sqrt(se_plan^2 + se_ref^2)``)."""
    (m, se), (mr, ser) = flight.expected(), ref.expected()
    if not (np.isfinite(m) and np.isfinite(mr)):
        return False, float("nan"), float("nan")
    tol = ERROR_SE * float(np.hypot(se, ser)) if np.isfinite(se) and np.isfinite(ser) else 0.0
    return bool(m - mr <= tol), m - mr, tol


#: ``--tiny``'s candidates: every kind of manoeuvre still offered (climbs, orbits at both distances,
#: library units, loop sweeps, anchor turns, revisits), at three elevations and the one-heading
#: library unit, about a third of the default's; the ranking, the greedy plan and the bound scale
#: with their number.
TINY_CANDIDATES: dict[str, Any] = {"elevations_deg": (-60.0, 0.0, 60.0), "library_loops": (1,)}


def _candidate_args(args: argparse.Namespace) -> dict[str, Any]:
    out: dict[str, Any] = dict(TINY_CANDIDATES) if args.tiny else {}
    if args.yaw_rate > 0:
        out["yaw_rate_deg_s"] = args.yaw_rate
    if args.arcs:
        out["arcs"] = True
    if args.no_sweeps:
        out["sweeps"] = False
    return out


def _fmt(d: dict[str, float]) -> str:
    return ", ".join(f"{n} {v:.2f}" for n, v in d.items()) or "-"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--presets", default="paper,ground")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--seeds", default="", help="several seeds, e.g. 0,1,2 (instead of --seed); a summary table follows")
    ap.add_argument("--order", type=int, default=10)
    ap.add_argument("--prior-std", type=float, default=0.0, help="the prior's pattern spread over the sphere [dB]; 0: the smoothing fit --degree auto "
                                                                                  "learns from the reference flight")
    ap.add_argument("--power", type=float, default=2.0, help="exponent of the smoothness prior's roughness weights")
    ap.add_argument("--correlated", choices=("reference", "own", "off"), default="reference",
                    help="the drifting error's size: from the complete reference flight, each flight's own blocks, or none")
    ap.add_argument("--posterior", choices=("inflated", "honest"), default="inflated",
                    help="with the learned prior: the noise times the variance inflation for every part (inflated), or the fit's "
                         "noise, the prior's variance times the inflation and the held-out misfit per direction cell (honest)")
    ap.add_argument("--budget", action="store_true",
                    help="split each flight's pattern error at its 2-dB point into bias, pointing and fading (slower)")
    ap.add_argument("--block-s", type=float, default=DEFAULT_BLOCK_S, help="length of a time block of the drifting error [s]")
    ap.add_argument("--draws", type=int, default=DRAWS,
                    help="independent noise draws of each flight plan for the expected error (0: the single-draw check only)")
    ap.add_argument("--yaw-rate", type=float, default=0.0, help="the candidates' cruise yaw rate [deg/s]; 0: CandidateOptions' default")
    ap.add_argument("--arcs", action="store_true", help="also arcs over or under the anchor among the candidates")
    ap.add_argument("--no-sweeps", action="store_true", help="leave out the loop sweeps (the paper unit's circles, one drone or both turning)")
    ap.add_argument("--tilt", action="store_true", help="the planners model the drones' steady tilt in the wind (from the start's poses)")
    ap.add_argument("--aggregate", choices=("rms", "max"), default="rms",
                    help="the ranking's score: the nodes' RMS spread (default) or the largest (the stop criterion's)")
    ap.add_argument("--rate", choices=("spread", "information"), default="information",
                    help="the ranking per second: the spread's inverse square's growth (default) or its reduction")
    ap.add_argument("--prefixes", type=int, default=ManoeuvreOptions().prefixes,
                    help="score each candidate's first k/N too and fly its best prefix (1: whole manoeuvres only)")
    ap.add_argument("--lookahead", type=int, default=ManoeuvreOptions().lookahead,
                    help="rank the best N candidates by rate again by their estimated time to the target (0: the rate alone)")
    ap.add_argument("--aimed", type=int, default=ManoeuvreOptions().aimed,
                    help="also candidates aimed at each node's N directions of largest posterior variance (0: the fixed ones only)")
    ap.add_argument("--design", choices=("rate", "end", "support"), default=ManoeuvreOptions().design,
                    help="rank by rate now (default) or by the criterion's gradient at the anticipated final posterior")
    ap.add_argument("--bound", choices=("", "yes", "only", "no"), default="",
                    help="print the optimal design's bound after the start (only: and fly nothing else; --tiny prints it "
                         "unless no)")
    ap.add_argument("--ranker", choices=("reference", "live", "live-targets"), default="reference",
                    help="the suggested flight's ranking: from the posterior learned on the complete reference flight (default), "
                         "or as rplearn live ranks, from its own refits of the flight so far, for each node's sphere "
                         "(live) or the benchmark's target directions (live-targets); with --hyper previous as rplearn "
                         "live --from-model ranks, with the earlier flight's model file while the session is young")
    ap.add_argument("--hyper", choices=HYPERS, default="reference",
                    help="the planners' noise, prior and drift: from the fit of this flight's reference (default), of an earlier "
                         f"flight of the same antennas (seed {PREVIOUS_SEED}), the CLI's defaults (no fit), or the CLI's "
                         "defaults with --noise and --drift from that earlier flight (flags)")
    ap.add_argument("--planners", choices=("both", "optimized", "suggested"), default="both",
                    help="fly the suggested flight and the optimized plan (both), or either alone (faster)")
    ap.add_argument("--tiny", action="store_true", help="the smoke preset at SH-4 (seconds; criteria not enforced)")
    args = ap.parse_args(argv)
    presets = ["smoke"] if args.tiny else [p.strip() for p in args.presets.split(",") if p.strip()]
    order = 4 if args.tiny else args.order
    draws = min(args.draws, 2) if args.tiny else args.draws
    seeds = [int(v) for v in args.seeds.split(",") if v.strip()] or [args.seed]
    failures = 0
    rows: list[str] = []
    diffs: dict[tuple[str, str], list[tuple[float, float]]] = {}
    for preset, seed in ((p, s) for p in presets for s in seeds):
        t0 = time.perf_counter()
        ref_total = _config(preset).campaign.with_role("learning")
        limit = float(sum(u.duration_s for u in ref_total.units))
        flights = run(preset, order, seed, limit, args.power, args.prior_std, args.correlated, args.block_s, args.posterior,
                      args.budget or args.tiny, draws, _candidate_args(args), args.tilt, args.aggregate,
                      args.rate, args.prefixes, args.lookahead, args.aimed, args.design, _bound_mode(args),
                      args.ranker, args.hyper, args.planners)
        ref = flights["reference"]
        if len(flights) == 1:  # --bound only
            continue
        print(f"{preset} (SH-{order}, seed {seed}, {time.perf_counter() - t0:.0f} s): time to {TARGET_DB:g} dB per-node spread")
        for f in flights.values():
            when = f"{f.reached_s:.0f} s" if f.reached_s is not None else "not reached" + (
                f" (its plan ends at {f.history[-1][0]:.0f} s with {f.history[-1][1]:.2f} dB)" if f.history else "")
            ratio = "" if f.reached_s is None or ref.reached_s is None or f is ref else f", ratio {f.reached_s / ref.reached_s:.2f}x"
            print(f"  {f.name:10s} {when}{ratio}; spread [{_fmt(f.spread_db)}] dB (own posterior [{_fmt(f.own_db)}]); "
                  f"pattern error [{_fmt(f.error_db)}] dB")
            if f.budget_db:
                print("    error by source (bias / pointing / fading, each fitted alone) ["
                      + ", ".join(f"{n} {b:.2f}/{p:.2f}/{w:.2f}" for n, (b, p, w) in f.budget_db.items()) + "] dB")
            if f.history:  # the largest spread every 20 s of flight: where it falls fast and where it stalls
                marks = [(t, v) for t, v in f.history if int(t // 20) != int((t - STEP_S) // 20)]
                print("    spread over time: " + ", ".join(f"{t:.0f} s {v:.2f}" for t, v in marks) + " dB")
            if f.steps:
                print("    " + "; ".join(f.steps[:16]) + (" ..." if len(f.steps) > 16 else ""))
            if f.draws_db:
                mean, se = f.expected()
                print(f"    {len(f.draws_db)} more draws of the same plan, cut at {f.reached_s:.0f} s: worst error "
                      f"[{', '.join(f'{v:.2f}' for v in f.draws_db)}] dB, mean {mean:.2f} +- {se:.2f} (s.e.); their largest "
                      f"spread [{', '.join(f'{v:.2f}' for v in f.draw_spreads_db)}] dB")
        for name in [n for n in ("suggested", "optimized") if n in flights]:
            f = flights[name]
            ok_time = f.reached_s is not None and ref.reached_s is not None and f.reached_s <= TIME_RATIO * ref.reached_s
            ok_one = bool(f.error_db) and bool(ref.error_db) and max(f.error_db.values()) <= max(ref.error_db.values()) + 0.05
            ok_err, diff, tol = expected_no_worse(f, ref)
            if np.isfinite(diff) and np.isfinite(tol):
                diffs.setdefault((preset, name), []).append((diff, tol / ERROR_SE))
            judged = ok_err if draws > 0 else ok_one
            print(f"  {name}: time [{'ok' if ok_time else 'MISS'}] error [{'ok' if judged else 'MISS'}] "
                  f"(expected: {diff:+.2f} dB against a tolerance of {tol:.2f} = {ERROR_SE:g} s.e.; single draw "
                  f"[{'ok' if ok_one else 'MISS'}] at +0.05 dB)")
            failures += 0 if (ok_time and judged) or args.tiny else 1
            when = "-" if f.reached_s is None or ref.reached_s is None else f"{f.reached_s:.0f} s ({f.reached_s / ref.reached_s:.2f}x)"
            worst = max(f.error_db.values()) if f.error_db else float("nan")
            (m, se), (mr, ser) = f.expected(), ref.expected()
            rows.append(f"| {preset} | {seed} | {name} | {ref.reached_s or float('nan'):.0f} s | {when} | "
                        f"{worst:.2f} / {max(ref.error_db.values()) if ref.error_db else float('nan'):.2f} | "
                        f"{m:.2f} +- {se:.2f} / {mr:.2f} +- {ser:.2f} | {diff:+.2f} (tol {tol:.2f}) | "
                        f"{'ok' if ok_time else 'miss'} / {'ok' if judged else 'miss'} |")
    if len(rows) > 2:
        print("\n| preset | seed | planner | reference | time to 2 dB | one draw: worst error / reference's [dB] | "
              f"{draws} draws: mean +- s.e. / reference's [dB] | difference | time / error |")
        print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
        print("\n".join(rows))
        print(f"{sum(r.endswith('ok / ok |') for r in rows)} of {len(rows)} cells meet both criteria")
        for (preset, name), v in diffs.items():  # the cells' differences pooled (independent draws: s.e. adds in quadrature)
            d, se = np.array(v).T
            print(f"{preset} {name}: expected error minus the reference's over {d.size} seeds {d.mean():+.2f} +- "
                  f"{np.sqrt(np.sum(se**2)) / d.size:.2f} dB (s.e.)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
