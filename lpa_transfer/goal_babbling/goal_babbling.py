"""Online goal babbling (thesis ch. 6, §6.3.1, Alg. 6; Rolf, Steil & Gienger 2010/2011).

As in explauto, three separate objects meet here: the environment (the robot, a
:class:`lpa_transfer.robots.kinematics.Kinematics`: joint limits, home posture, and ``forward(Q) -> X``,
which executes commands and returns the observed end-effector positions — a simulator or a
real robot may stand behind it), the sensorimotor model
(:class:`lpa_transfer.learners.sensorimotor.SensorimotorModel`) and the exploration strategy
(:class:`GoalBabbling`, with its noise :class:`ExplorationNoise`).

One movement of Alg. 6: a goal x_g is drawn uniformly in ``x_bounds``; T sub-targets lead to
it on the straight line from where the movement starts; each step commands the inverse
model's answer plus exploration noise (eq. 6.1, a slowly drifting random linear function of
the sub-target), clipped into the joint limits, and the model learns the observed (q, x).
With probability ``p_home`` a movement returns home instead (Rolf et al. 2011; not in
Alg. 6). ``steps_per_second`` fixes the samples per simulated second, which the thesis does
not give. The sub-targets, the noise's random walk, the home returns and our values for what
the thesis leaves open: docs/library.md, "Goal babbling". The same seed gives the same run
bit for bit.
"""
import numpy as np

from lpa_transfer import _validation as check
from lpa_transfer._validation import check_x_bounds
from lpa_transfer.learners.sensorimotor import make_sensorimotor_model
from lpa_transfer.robots.kinematics import execute, home_pose


def subtargets(start, goal, n_subtargets):
    """The T = ``n_subtargets`` points (T, m) on the straight line from ``start`` (excluded) to
    ``goal`` (the last point): x_t = (1 − t/T)·x_0 + (t/T)·x_g, t = 1..T (Alg. 6 l. 7)."""
    start, goal = np.asarray(start, dtype=np.float64), np.asarray(goal, dtype=np.float64)
    fractions = np.arange(1, n_subtargets + 1)[:, None] / n_subtargets
    return (1.0 - fractions) * start + fractions * goal


class ExplorationNoise:
    """E_t(x*) = A_t x* + b_t (eq. 6.1), drifting as a normalised random walk (module
    docstring). ``rng`` is a ``numpy.random.Generator``; ``A_`` (d, m) and ``b_`` (d,) are the
    current parameters."""

    def __init__(self, n_joints, n_task, sigma, drift, rng):
        check.check_float(sigma, "sigma", 0)
        check.check_float(drift, "drift", 0)
        self.sigma, self.drift, self.rng = sigma, drift, rng
        self.A_ = rng.normal(0.0, sigma, (n_joints, n_task))
        self.b_ = rng.normal(0.0, sigma, n_joints)
        self._shrink = 1.0 / np.sqrt(1.0 + (drift / sigma) ** 2) if sigma > 0 else 0.0

    def __call__(self, x):
        """The noise E_t(x) (d,) for a task point x (m,)."""
        return self.A_ @ x + self.b_

    def step(self):
        """One step of the random walk: A_{t+1}, b_{t+1}."""
        self.A_ = (self.A_ + self.rng.normal(0.0, self.drift, self.A_.shape)) * self._shrink
        self.b_ = (self.b_ + self.rng.normal(0.0, self.drift, self.b_.shape)) * self._shrink


class GoalBabbling:
    """Online goal babbling, Alg. 6 (module docstring); the constructor takes hyperparameters.

    Parameters
    ----------
    x_bounds : (low, high)
        X_bounds, the box in task space the goals are drawn from.
    n_subtargets : int
        T, the sub-targets (steps) of one movement; the last is the goal.
    home : sequence or None
        q_home (within the joint limits); None: the environment's home.
    sigma, drift : float
        σ and σ_Δ of the exploration noise (module docstring).
    p_home : float
        Probability of a return to home after a goal movement.
    steps_per_second : float
        Samples per simulated second (module docstring).
    seed : int
        Seeds every random choice.

    :meth:`start` binds an environment and a model and initialises L⁻¹ with (x_home, q_home);
    then :meth:`step`, :meth:`run` or :meth:`run_for` explore. State: ``environment_``,
    ``model_``, ``noise_``, ``steps_`` (samples so far), ``time_`` (simulated s), ``position_``
    and ``command_`` (the last observed x and executed q), ``goal_`` (of the movement under
    way: x_home for a return home).
    """

    def __init__(self, x_bounds, n_subtargets=10, home=None, sigma=0.1, drift=0.01, p_home=0.1,
                 steps_per_second=10.0, seed=0):
        self.x_bounds = x_bounds
        self.n_subtargets = n_subtargets
        self.home = home
        self.sigma = sigma
        self.drift = drift
        self.p_home = p_home
        self.steps_per_second = steps_per_second
        self.seed = seed

    def start(self, environment, model=None):
        """Begin exploring ``environment`` (a Kinematics) with ``model`` (default: a fresh
        K = 3 nearest-neighbour SensorimotorModel): L⁻¹ ← train(q_home, x_home) (Alg. 6 l. 4)."""
        check.check_int(self.n_subtargets, "n_subtargets", 1)
        check.check_float(self.steps_per_second, "steps_per_second", 0)
        check.check_float(self.p_home, "p_home", 0)
        check.check_int(self.seed, "seed", 0)
        if self.p_home > 1 or self.steps_per_second == 0:
            raise ValueError(f"need p_home <= 1 and steps_per_second > 0, got p_home="
                             f"{self.p_home!r}, steps_per_second={self.steps_per_second!r}")
        limits = np.asarray(environment.joint_limits, dtype=np.float64)
        q_home = home_pose(limits, environment.home if self.home is None else self.home,
                           name="GoalBabbling home")
        q_home, x_home = self._execute(environment, q_home)
        self._low, self._high = check_x_bounds(self.x_bounds, len(x_home))
        goal_stream, noise_stream = np.random.SeedSequence(self.seed).spawn(2)
        self._rng = np.random.default_rng(goal_stream)
        self.noise_ = ExplorationNoise(len(q_home), len(x_home), self.sigma, self.drift,
                                       np.random.default_rng(noise_stream))
        self.environment_, self._limits = environment, limits
        self._q_home, self._x_home = q_home, x_home
        self.model_ = make_sensorimotor_model() if model is None else model
        self.model_.update(q_home[None], x_home[None])
        self.position_, self.command_, self.goal_ = x_home, q_home, None
        self.steps_, self._plan, self._plan_kind = 0, [], None
        return self

    def _check_started(self):
        if not hasattr(self, "model_"):
            raise ValueError("call start(environment, model) before exploring")

    @staticmethod
    def _execute(environment, q):
        """Run one command: the observed (q, x) (:func:`lpa_transfer.robots.kinematics.execute`)."""
        positions, points = execute(environment, q[None])
        return positions[0], points[0]

    @property
    def time_(self):
        """Simulated seconds explored so far."""
        return self.steps_ / self.steps_per_second

    def _next_movement(self):
        """Plan T steps: sub-targets x_t towards a random goal, or, after a goal movement
        and with probability p_home, joint-space waypoints q_t back to q_home."""
        going_home = self._rng.random() < self.p_home and self._plan_kind == "goal"
        if going_home:
            self.goal_ = self._x_home
            path = subtargets(self.command_, self._q_home, self.n_subtargets)
        else:
            self.goal_ = self._rng.uniform(self._low, self._high)
            path = subtargets(self.position_, self.goal_, self.n_subtargets)
        self._plan_kind = "home" if going_home else "goal"
        self._plan = list(path[::-1])

    def step(self):
        """One step of Alg. 6 (l. 9-12): returns the observed q (the command, on a kinematic
        environment) and x; ``sent_`` is the command itself."""
        self._check_started()
        if not self._plan:
            self._next_movement()
        point = self._plan.pop()
        if self._plan_kind == "goal":
            q = self.model_.infer_command(point[None])[0] + self.noise_(point)
        else:
            q = point
        self.sent_ = np.clip(q, self._limits[:, 0], self._limits[:, 1])
        q, x = self._execute(self.environment_, self.sent_)
        self.model_.update(q[None], x[None])
        self.noise_.step()
        self.position_, self.command_ = x, q
        self.steps_ += 1
        return q, x

    def run(self, n_steps, callback=None, every=None):
        """Explore ``n_steps`` steps: ``(Q, X)``, the observed joint positions (n_steps, d) and
        task positions (n_steps, m); ``commands_`` holds the commands sent (equal to Q on a
        kinematic environment). ``callback(self)`` is called whenever ``steps_`` reaches a
        multiple of ``every`` (e.g. to evaluate the model)."""
        self._check_started()
        check.check_int(n_steps, "n_steps", 0)
        if callback is not None:
            check.check_int(every, "every", 1)
        observed, positions, sent = [], [], []
        for _ in range(n_steps):
            q, x = self.step()
            observed.append(q)
            positions.append(x)
            sent.append(self.sent_)
            if callback is not None and self.steps_ % every == 0:
                callback(self)
        self.commands_ = np.reshape(sent, (n_steps, len(self._q_home)))
        return (np.reshape(observed, (n_steps, len(self._q_home))),
                np.reshape(positions, (n_steps, len(self._x_home))))

    def run_for(self, seconds, callback=None, interval=None):
        """:meth:`run` for ``seconds`` simulated seconds, ``callback(self)`` every ``interval``
        s (both rounded to whole steps); ``self.time_`` says when a callback happens."""
        check.check_float(seconds, "seconds", 0)
        every = None
        if callback is not None:
            check.check_float(interval, "interval", 0)
            every = max(1, int(round(interval * self.steps_per_second)))
        return self.run(int(round(seconds * self.steps_per_second)), callback, every)
