r"""Periodic motions followed through a parameter: pseudo-arclength continuation of the fixed
points of the period map, their stability from the Floquet multipliers, and their
bifurcations, detected and located.

A *family* is what continuation needs of a periodically forced system at a parameter p:
`map(x, p, multiple)`, the state x (scaled coordinates: a unit is the system's own small
length, e.g. a clearance) advanced over `multiple` forcing periods, and `measure(x, p,
multiple)`, what the orbit through x shows (its response `amplitude`, in the system's units;
its smallest `gap` to contact over the orbit, m, negative when in contact; None without
contacts). The mechanism's family (reduced.dynamics.studies.MechanismFamily) rebuilds the
model at p; the tests give a linear and a Duffing oscillator the same way.

Periodic orbits are the zeros of G(x, p) = P(x; p) - x. Continuation [Seydel2010] on the
branch u = (x, q), q = (p - p_low) / (p_high - p_low) the parameter across its range: from a
point u_k with unit tangent t_k, predict u = u_k + ds t_k and correct by Newton on

    G(x, p) = 0,      t_k . (u - u_k) - ds = 0,

with the Jacobian [P_x - I, P_q; t_k^T] of u_k (chord iterations; computed again at the
iterate when the residual does not halve), until |G| <= tol (1 + |x|), tol the family's
(what its integration resolves: 100 rtol for a mechanism, where at 10 rtol the corrector
meets the noise of the impacts' location; NEWTON_TOL at least). An iterate farther than
CORRECTOR_REACH steps from u_k has left the branch, and the step is retried shorter
(measured: on the slider-crank with friction a corrector from 95 rpm ran to 69, 53 and
11 rpm, each period at 11 rpm five times longer to integrate). P_x, the monodromy matrix,
and P_q by central differences of the map (a step h in x, in scaled units, and of the
range in q, FD_STEP or, where the integration's noise needs it, a larger one chosen at the
first orbit, `resolve`; P_x of a mechanism along the tangent space of its ideal joints and drive only,
`directions`: on the Flores slider-crank 3.8 -> 1.0 s a monodromy): each perturbed state
meets its contact onsets at its own (shifted) instants, so the difference quotient is the
derivative of the map through the impacts, the saltation of each onset included. Its step
lies between what the integration resolves and the depth of an impact: on an impacting orbit
of the impact oscillator (rtol 1e-8, 6.5 um deep into a 1 mm clearance) the trace and
determinant of the monodromy's block across the guide are 0.13 % and 0.26 % off an
independent integration at the step 1e-4 (0.1 um), 2.6 % and 5 % at 1e-5 and 21 % at 1e-6,
where the noise of the onsets' location (the impact speed v0 of the damping law) takes over.
The tangent at a converged point is the null vector of [P_x - I, P_q], oriented along the
secant from the last point (oriented along the last tangent, the slider-crank's branch with
friction turned back at 103 rpm and retraced its own orbits, a fold that was not one: its
largest multiplier lies between 0.12 and 0.35 from orbit to orbit). What the monodromy
resolves of the stability is measured at the first orbit (the spread: the largest
multiplier's move when the difference step doubles), where the step is chosen as the
smallest that resolves it (`resolve`), and warned of above SPREAD_WARNING. Step control: ds
grows by 1.5 after a corrector that needed at most four (chord) iterations and halves after
one that needed more than seven, up to 50 times the first step; a failed step is retried
down to ds_min, then once at two and four times the step (over a branch point, where the
extended Jacobian is singular), and the branch stops with the reason, its points kept.

Stability: the eigenvalues of P_x are the Floquet multipliers; the orbit is stable when all
lie inside the unit circle. Bifurcations between consecutive points, each by a test
function that changes sign there (or is exactly zero at the later point; a value that is
not finite is no change). A product of factors changes sign for an odd number of
crossings only: a step over which two real multipliers passed -1 (or +1), or two complex
pairs the circle, is retried shorter until they part (`paired`; on two flips a tenth of
the first step apart, each is then found), unless the orbit grazes in it (the multipliers
jump there anyway). A map that is not finite (an integration that failed without saying
so) is a failed orbit, as one that stops is:
- fold (limit point, the jump of a frequency response): the tangent's q-component t_q and
  det(P_x - I) together (t_q is det(P_x - I) times the tangent's orientation: t_q changing
  alone is the orientation flipping, which `oriented` turns back);
- branch point: a real multiplier passes +1 where the branch does not fold (a pitchfork,
  e.g. a symmetric orbit turning asymmetric): det(P_x - I) = prod (mu_i - 1);
- period doubling: a real multiplier passes -1: det(P_x + I) = prod (mu_i + 1); the
  doubled branch is switched onto there (`doubled`);
- Neimark-Sacker (torus): a complex pair passes the unit circle: prod_(i<j) (mu_i mu_j - 1)
  (the bialternate product's determinant), where the count of complex multipliers outside
  the circle changes (a real pair with mu_i mu_j = 1, a neutral saddle, is no torus);
- grazing: the orbit's smallest gap to contact passes 0, where impacting motion is born.
  A change of the multipliers or of t_q between two points where the orbit grazes is the
  grazing's once the step is cut (halved, each half corrected onto the branch) to
  GRAZING_WIDTH of the range around it: the multipliers jump there, and the branch may
  turn without smoothness (a nonsmooth fold), while a bifurcation just past the grazing
  falls in a piece of its own. Where no orbit continues the branch past it, the branch stops at it,
  located by extrapolating the gap of its last two points.
Fold, branch point, period doubling and Neimark-Sacker are located on the arclength from
the last point before them, every trial corrected onto the branch, by Illinois regula falsi
(bracketed), until the parameter moves less than LOCATE_TOL of the range. Grazing is located
along the orbits without contact alone, each by Newton at fixed p, where the gap is smooth:
on the other side a stiff contact's shallow penetration keeps the gap near zero over a range
of the parameter (a bracketing secant stalled there, 0.03 % of the frequency off on the
impact oscillator), and at a nonsmooth fold the grazing lies beyond both points in p.
"""

import math
from dataclasses import dataclass, field

import numpy as np
from tqdm import tqdm

FD_STEP = 1e-4            # central-difference step of the monodromy (scaled x) and of q
NEWTON_TOL = 1e-9         # |G| <= tol (1 + |x|): a periodic orbit; tol the family's, at least this
CORRECTOR_ITERATIONS = 10
CORRECTOR_REACH = 10.0    # a corrector iterate farther than this many steps from the last point has left
SWITCH_GROWTH = 10.0      # a guess for the doubled orbit whose Newton residual grows this much is left
GROW, SHRINK = 1.5, 0.5
LOCATE_ITERATIONS = 6
LOCATE_TOL = 1e-6         # of the parameter range
GRAZING_WIDTH = 1e-5      # of the range: a step over a grazing is cut down to this around it
SPREAD_WARNING = 0.01     # a move of the largest multiplier (step doubled) above this is warned of
STEP_DOUBLINGS = 8        # difference steps tried at the first orbit: FD_STEP .. 128 FD_STEP
TANGENT_RANK = 1e-6       # a projection derivative's singular value below this (of the largest): normal


@dataclass
class Point:
    """A periodic orbit on the branch: its state x, parameter p, the unit tangent (x, q),
    its Floquet multipliers and what the family measures of it."""

    x: np.ndarray
    p: float
    tangent: np.ndarray
    multipliers: np.ndarray
    measures: dict
    iterations: int = 0
    jacobian: np.ndarray | None = field(default=None, repr=False)   # [P_x - I, P_q] here

    @property
    def largest(self) -> float:
        """The largest multiplier's modulus."""
        return float(np.max(np.abs(self.multipliers)))

    @property
    def stable(self) -> bool:
        return self.largest < 1.0


@dataclass
class Special:
    """A bifurcation located on the branch: its kind, parameter, the point there, and the
    index of the first branch point after it."""

    kind: str
    p: float
    point: Point
    after: int
    side: float = 0.0   # period doubling: the direction in p where a multiplier lies beyond -1


@dataclass
class Branch:
    points: list = field(default_factory=list)
    specials: list = field(default_factory=list)
    multiple: int = 1
    complete: bool = True
    reason: str = ""


class Continuation:
    """Pseudo-arclength continuation of the period-`multiple` orbits of `family` in p across
    [low, high]."""

    def __init__(self, family, low: float, high: float, multiple: int = 1):
        self.family, self.low, self.high, self.multiple = family, low, high, multiple
        self.width = high - low
        self.step = FD_STEP   # the difference step of the monodromy and of P_q (`resolve`)
        self.bar = None   # the running branch's progress bar

    def say(self, doing: str) -> None:
        """What the branch is doing between two points, on its progress bar: the corrector's
        iterations, a step retried shorter, a bifurcation located each cost monodromies
        (2n + 2 integrations of the orbit), and minutes can pass between points (measured:
        over ten on the slider-crank with friction near 100 rpm, rtol 4e-8)."""
        if self.bar is not None:
            self.bar.set_postfix_str(doing, refresh=True)

    # -- the map, its residual and derivatives in u = (x, q)
    def q(self, p: float) -> float:
        return (p - self.low) / self.width

    def p(self, q: float) -> float:
        return self.low + q * self.width

    def mapped(self, x, p):
        """The family's map, FloatingPointError when it is not finite (an integration that
        failed without saying so: every caller treats that error as a failed orbit)."""
        y = self.family.map(x, p, self.multiple)
        if not np.all(np.isfinite(y)):
            raise FloatingPointError(f"the map at {p:.6g} is not finite")
        return y

    def residual(self, x, p):
        return self.mapped(x, p) - x

    def directions(self, x, p):
        """The directions the monodromy is differenced along and what turns their quotients
        into P_x: (D, W) with P_x = (P_x D) W. The coordinates (D = W = I), or, for a family
        whose map first moves x onto its constraints (family.consistent: C), the r
        directions of their tangent space: P = P o C gives P_x = P'(C(x)) C_x, and
        C_x = T T^T C_x with T an orthonormal basis of C_x's range (its singular values
        above TANGENT_RANK of the largest), so D = T and W = T^T C_x: 2r integrations of the
        orbit instead of 2n (the Flores slider-crank: r = 4 of n = 18), C_x by central
        differences of the projection, no integration."""
        n = x.size
        consistent = getattr(self.family, "consistent", None)
        if consistent is None:
            return None, None
        onto = np.empty((n, n))
        for i in range(n):
            dx = np.zeros(n)
            dx[i] = FD_STEP
            onto[:, i] = (consistent(x + dx, p) - consistent(x - dx, p)) / (2 * FD_STEP)
        u, sigma, _ = np.linalg.svd(onto)
        tangent = u[:, sigma > TANGENT_RANK * sigma[0]]
        if tangent.shape[1] == n:
            return None, None
        return tangent, tangent.T @ onto

    def jacobian(self, x, p, step: float | None = None):
        """[P_x - I, P_q] at (x, p) by central differences (P_x along `directions`, at `step`
        in x, and P_q at `step` in q; the branch's difference step by default)."""
        step = self.step if step is None else step
        n = x.size
        jac = np.empty((n, n + 1))
        along, onto = self.directions(x, p)
        if along is None:
            for i in range(n):
                dx = np.zeros(n)
                dx[i] = step
                jac[:, i] = (self.residual(x + dx, p) - self.residual(x - dx, p)) / (2 * step)
        else:
            quotients = np.column_stack([
                (self.mapped(x + step * d, p) - self.mapped(x - step * d, p)) / (2 * step)
                for d in along.T])
            jac[:, :n] = quotients @ onto - np.eye(n)
        q = self.q(p)
        jac[:, n] = (self.mapped(x, self.p(q + step)) - self.mapped(x, self.p(q - step))) / (2 * step)
        return jac

    def resolve(self, point: Point) -> tuple[Point, float | None]:
        """The branch's difference step, chosen at its first orbit: the smallest h = FD_STEP 2^k
        at which the largest multiplier's modulus moves by at most SPREAD_WARNING / 2 each
        time the step doubles twice (h -> 2h -> 4h; one doubling alone passes by chance on
        noise: on a noisy linear map, 0.003 at FD_STEP where the multiplier was 0.017 off).
        The quotients carry the integration's error over the step as noise, which falls as
        the step grows; their truncation grows with it. Returns the orbit with its monodromy
        at h and the spread there, the larger of the two moves (what the monodromy resolves
        of the orbit's stability); where no step up to FD_STEP 2^(STEP_DOUBLINGS - 1) passes,
        the one of the smallest spread; spread None when no doubled step integrates.
        Measured on the Flores slider-crank with friction (rtol 4e-8, the journal sliding
        in contact): at 100 rpm the largest multiplier is -0.305, -0.286, -0.316 at steps
        1e-4, 2e-4, 3e-4 and -0.282 .. -0.298 from 6e-4 to 1e-2; at 160 rpm -0.40 at 3e-4,
        a scatter up to 0.11 in modulus to 2e-3, and 0.045-0.048 at 3e-3 and 6e-3, as at
        rtol 1e-10 (0.02-0.07 from 3e-4 to 6e-3). The impact oscillator and the shaken panel
        (moves below 1e-5) keep FD_STEP."""
        ladder = [point]   # the orbit at FD_STEP 2^k
        windows = []       # (-doublings, spread, k): two doublings first, then the smallest spread
        for k in range(1, STEP_DOUBLINGS):
            try:
                ladder.append(self.point(point.x, point.p, point.tangent, point.iterations,
                                         point.measures, FD_STEP * 2 ** k))
            except FloatingPointError:
                break
            moves = [abs(ladder[j].largest - ladder[j - 1].largest) for j in range(max(1, k - 1), k + 1)]
            windows.append((-len(moves), max(moves), k - len(moves)))
            if len(moves) == 2 and max(moves) <= SPREAD_WARNING / 2:
                break
        if not windows:
            return point, None
        _, spread, k = min(windows)
        self.step = FD_STEP * 2 ** k
        return ladder[k], spread

    def point(self, x, p, previous_tangent=None, iterations=0, measures=None, step=None) -> Point:
        """The converged orbit at (x, p): monodromy (at the difference step `step`, the
        branch's by default), multipliers, tangent and measures (the family's, unless the
        orbit's are given)."""
        jac = self.jacobian(x, p, step)
        tangent = null_vector(jac)
        if previous_tangent is not None and tangent @ previous_tangent < 0:
            tangent = -tangent
        monodromy = jac[:, :-1] + np.eye(x.size)
        if measures is None:
            measures = self.family.measure(x, p, self.multiple)
        return Point(x, p, tangent, np.linalg.eigvals(monodromy), measures, iterations, jac)

    def converged(self, g, x) -> bool:
        tol = max(NEWTON_TOL, getattr(self.family, "tolerance", NEWTON_TOL))
        return float(np.linalg.norm(g)) <= tol * (1.0 + float(np.linalg.norm(x)))

    # -- the first point: Newton at fixed p
    def first(self, x, p, direction: float, iterations: int = 2 * CORRECTOR_ITERATIONS,
              growth: float = math.inf) -> Point:
        """The orbit at p from the guess x (Newton, the monodromy every iteration), its tangent
        pointing to increasing p when direction > 0. FloatingPointError when it does not
        converge in `iterations`, or when a residual exceeds `growth` times the first (a
        guess Newton leaves)."""
        history = self.residuals = []   # |G| at each iteration, kept for the caller
        for k in range(iterations + 1):   # the last update is tested too
            g = self.residual(x, p)
            history.append(float(np.linalg.norm(g)))
            if history[-1] > growth * history[0]:
                break
            if self.converged(g, x):
                start = self.point(x, p)
                if start.tangent[-1] * direction < 0:
                    start.tangent = -start.tangent
                return start
            if k == iterations:
                break
            jac = self.jacobian(x, p)
            x = x + np.linalg.lstsq(jac[:, :-1], -g, rcond=None)[0]
        raise FloatingPointError(f"the first periodic orbit at {p:.6g} did not converge "
                                 f"(residuals {', '.join(f'{r:.2e}' for r in history)})")

    # -- a step along the branch
    def correct(self, start: Point, ds: float):
        """Corrector from the prediction start + ds t: (x, p, G, iterations) or None."""
        t = start.tangent
        u0 = np.append(start.x, self.q(start.p))
        u = u0 + ds * t
        jac = None if start.jacobian is None else np.vstack([start.jacobian, t])   # chord from the start
        last = math.inf
        for k in range(1, CORRECTOR_ITERATIONS + 1):
            x, p = u[:-1], self.p(u[-1])
            if not self.low - self.width <= p <= self.high + self.width \
                    or np.linalg.norm(u - u0) > CORRECTOR_REACH * abs(ds):
                return None
            try:
                g = self.residual(x, p)
            except FloatingPointError:
                return None
            norm = float(np.linalg.norm(g))
            if self.converged(g, x):
                return x, p, g, k
            self.say(f"from {start.p:.6g} to {p:.6g}: corrector iteration {k}, |G| {norm:.2g}")
            if jac is None or norm > 0.5 * last:
                try:
                    jac = np.vstack([self.jacobian(x, p), t])
                except FloatingPointError:
                    return None
            last = norm
            extended = np.append(g, t @ (u - u0) - ds)
            u = u - np.linalg.solve(jac, extended)
        return None

    def run(self, start: Point, ds: float, max_points: int, progress: bool = False,
            ds_max: float | None = None) -> Branch:
        """The branch from `start` (its tangent gives the direction) until it leaves [low,
        high], has max_points points, or a step fails at ds_min = ds / 1000; steps up to
        ds_max (default 50 ds)."""
        branch = Branch([start], multiple=self.multiple)
        ds_min, ds_max = ds / 1000, ds * 50 if ds_max is None else ds_max
        bar = tqdm(total=max_points, desc="continuation", unit="point", disable=not progress, initial=1)
        self.bar = bar if progress else None
        while len(branch.points) < max_points:
            last = branch.points[-1]
            step = ds
            found = None
            self.say(f"at {last.p:.6g}")
            while found is None and step >= ds_min:
                found = self.correct(last, step)
                if found is None:
                    step *= SHRINK
                    self.say(f"at {last.p:.6g}, step retried at {step / ds:.3g} of the last")
            for jump in (2 * ds, 4 * ds):   # over a point where the corrector cannot converge
                if found is None:
                    step = jump
                    self.say(f"at {last.p:.6g}, a step {jump / ds:g} times the last")
                    found = self.correct(last, step)
            if found is None:
                branch.complete = False
                graze = self.grazing_end(branch.points)
                if graze is not None:
                    branch.specials.append(graze)
                    branch.reason = (f"the branch ends where its orbit grazes, at {graze.p:.6g}: the "
                                     "impacting orbits born there do not continue it smoothly")
                else:
                    branch.reason = (f"a step from {last.p:.6g} did not converge down to ds = "
                                     f"{ds_min:.3g}; the points before it are kept")
                break
            x, p, _, iterations = found
            try:
                secant = np.append(x - last.x, self.q(p) - self.q(last.p))
                new = oriented(last, self.point(x, p, secant, iterations))
            except FloatingPointError as err:
                branch.complete, branch.reason = False, f"at {p:.6g}: {err}"
                break
            if paired(last, new) and not grazes(last, new) and step * SHRINK >= ds_min:
                ds = step * SHRINK   # two multipliers crossed together: a shorter step parts them
                self.say(f"at {last.p:.6g}, two multipliers crossed in one step: retried shorter")
                continue
            branch.specials += self.specials(last, new, step, len(branch.points))
            branch.points.append(new)
            bar.update()
            ds = min(step * GROW, ds_max) if iterations <= 4 else (step * SHRINK if iterations > 7 else step)
            if not self.low <= p <= self.high:
                break
        bar.close()
        self.bar = None
        return branch

    @staticmethod
    def grazing_end(points) -> Special | None:
        """Grazing where a branch stops short of contact: the gap of its last two points,
        both without contact, extrapolated linearly in p to zero within the last step (the
        orbit reaching the gap, from where no orbit continues it smoothly: a nonsmooth fold);
        None otherwise."""
        if len(points) < 2:
            return None
        a, b = points[-2:]
        ga, gb = a.measures.get("gap"), b.measures.get("gap")
        if ga is None or gb is None or not 0 <= gb < ga:
            return None
        p = b.p + (b.p - a.p) * gb / (ga - gb)
        if abs(p - b.p) > abs(b.p - a.p):
            return None
        return Special("grazing", p, b, len(points))

    # -- the doubled branch
    def doubled(self, special: Special, ds: float, max_points: int, progress: bool = False) -> Branch | None:
        """The period-2m branch born at a period doubling, by switching onto it: from the
        orbit x* there along the eigenvector v of the multiplier nearest -1, the doubled
        orbit at p* + h (h a hundredth of the range, first towards where one more multiplier
        lies beyond -1: the supercritical side; then the other, where a subcritical doubling
        has its unstable doubled orbit) is found by Newton on P^2m from x* +- e v
        (amplitudes e from 1e-3 to 1 of the orbit's size: the doubled orbit grows as
        sqrt(h)), kept when P^m moves it (a genuine period 2m), and continued away from p*.
        A guess gets the corrector's iterations and is left when its residual grows
        SWITCH_GROWTH-fold (so a spurious doubling costs at most 16 x 10 monodromies). None
        when no doubled orbit is found."""
        point = special.point
        if point.jacobian is None:
            return None
        mu, vectors = np.linalg.eig(point.jacobian[:, :-1] + np.eye(point.x.size))
        k = int(np.argmin(np.abs(mu + 1.0)))
        v = np.real(vectors[:, k])
        v /= np.linalg.norm(v)
        side = special.side or 1.0
        twice = Continuation(self.family, self.low, self.high, 2 * self.multiple)
        twice.step = self.step   # the difference step the branch resolved its multipliers at
        size = 1.0 + float(np.linalg.norm(point.x))
        guesses = [(a, sign, way) for way in (side, -side) for a in (1e-3, 1e-2, 1e-1, 1.0)
                   for sign in (1.0, -1.0)]
        for amplitude, sign, way in tqdm(guesses, desc=f"switching at {point.p:.6g}", unit="guess",
                                         disable=not progress, leave=False):
            p = point.p + way * 0.01 * self.width
            try:   # a guess whose residual grows tenfold, or that does not converge as a
                #    corrector does, is left for the next
                start = twice.first(point.x + sign * amplitude * size * v, p, way,
                                    CORRECTOR_ITERATIONS, SWITCH_GROWTH)
            except FloatingPointError:
                continue
            try:
                once = self.mapped(start.x, p) - start.x
            except FloatingPointError:
                continue
            if np.linalg.norm(once) > 1e3 * NEWTON_TOL * size and \
                    np.linalg.norm(once) > 10 * getattr(self.family, "tolerance", 0.0) * size:
                return twice.run(start, ds, max_points, progress)
        return None

    # -- bifurcations
    def specials(self, a: Point, b: Point, ds: float, index: int) -> list:
        """The bifurcations between consecutive points a and b, located. A real multiplier
        passing +1 (det(P_x - I) changes sign) is the fold when t_q changes sign too, a
        branch point otherwise; t_q alone is no fold (`oriented` keeps it from flipping).
        Where the orbit grazes between them, the multipliers jump (the map's derivative is
        not continuous there) and the branch may turn (a nonsmooth fold): these changes
        belong to the grazing, which reports them, once the step is cut down to
        GRAZING_WIDTH of the range around it (`near_grazing`): a bifurcation just past the
        grazing is found in its own piece."""
        grazing = grazes(a, b)
        if grazing and (paired(a, b) or any(changes(TESTS[kind](a), TESTS[kind](b)) for kind in TESTS
                                            if kind != "grazing")):
            pieces = self.near_grazing(a, b, ds)
            if pieces is not None:
                return [s for left, right, length in pieces for s in self.specials(left, right, length, index)]
        found = []
        folded = changes(TESTS["fold"](a), TESTS["fold"](b)) and changes(TESTS["branch_point"](a),
                                                                          TESTS["branch_point"](b))
        torus = _outside_complex(a) != _outside_complex(b)
        for kind, test in TESTS.items():
            if not changes(test(a), test(b)) or (kind == "branch_point" and folded) \
                    or (kind == "fold" and not folded) or (kind == "neimark_sacker" and not torus) \
                    or (grazing and kind != "grazing"):
                continue
            at = self.locate(kind, test, a, b, ds)
            # the side where one more real multiplier lies beyond -1 (at lies between a and b)
            beyond, other = (b, a) if crossings(b)[0] > crossings(a)[0] else (a, b)
            found.append(Special(kind, at.p, at, index, math.copysign(1.0, beyond.p - other.p)))
        found.sort(key=lambda s: abs(s.p - a.p))
        return found

    def near_grazing(self, a: Point, b: Point, ds: float):
        """The step from a to b, over which the orbit grazes and another test function changes
        sign, cut in two at its middle (corrected onto the branch): the pieces as (left,
        right, arclength), or None where the step spans at most GRAZING_WIDTH of the range in
        p or its middle cannot be corrected (the changes then stay the grazing's). The
        piece that holds the grazing is cut again by `specials` until the other changes lie
        outside it (measured: the impact oscillator's symmetry-breaking branch point 5 mHz
        above its grazing at 14.264 Hz, inside a step of 0.03 Hz)."""
        if abs(b.p - a.p) <= GRAZING_WIDTH * self.width:
            return None
        self.say(f"cutting the step from {a.p:.6g} to {b.p:.6g} around a grazing")
        middle = self.trial(a, ds / 2)
        if middle is None or not min(a.p, b.p) <= middle.p <= max(a.p, b.p):
            return None
        return [(a, middle, ds / 2), (middle, b, self.arclength(middle, b))]

    def locate(self, kind, test, a: Point, b: Point, ds: float) -> Point:
        """The zero of `test` between a (arclength 0) and b (ds), each trial corrected onto
        the branch from a: Illinois regula falsi (the zero stays bracketed, and the end kept
        twice has its value halved, so that a one-sided approach cannot stall); a grazing
        point from the side without contact (one_sided). The trial nearest the zero is the
        point reported."""
        self.say(f"locating a {kind.replace('_', ' ')} between {a.p:.6g} and {b.p:.6g}")
        if kind == "grazing":
            return self.one_sided(test, a, b, ds)
        s_a, f_a, s_b, f_b = 0.0, test(a), ds, test(b)
        best, f_best = (a, f_a) if abs(f_a) < abs(f_b) else (b, f_b)
        kept = 0
        for _ in range(LOCATE_ITERATIONS):
            trial = self.trial(a, s_a + (s_b - s_a) * f_a / (f_a - f_b))
            f = None if trial is None else test(trial)
            if f is None:
                break
            moved = abs(trial.p - best.p) / self.width
            if abs(f) < abs(f_best):
                best, f_best = trial, f
            s = self.arclength(a, trial)
            if f * f_a > 0:
                s_a, f_a = s, f
                f_b, kept = (f_b / 2, kept + 1) if kept >= 0 else (f_b, 1)
            else:
                s_b, f_b = s, f
                f_a, kept = (f_a / 2, kept - 1) if kept <= 0 else (f_a, -1)
            if moved < LOCATE_TOL or f == 0:
                break
        return best

    def one_sided(self, test, a: Point, b: Point, ds: float) -> Point:
        """Grazing: the gap is smooth along the orbits without contact and flat on the other
        side (a stiff contact's shallow penetration), and the branch may turn there (a
        nonsmooth fold: the grazing then lies beyond both points in p), so the zero is found
        in p along the orbits without contact alone, each by Newton at fixed p from the
        nearest one: the root of the polynomial through the last (up to three) of them,
        within the bracket they make with the nearest p whose orbit touches (or where Newton
        did not converge), its midpoint where the root falls outside it."""
        if test(a) < 0:   # the branch comes from contact
            a, b = b, a
        outside = [(a.p, test(a), a)]
        inside = None
        step = 0.01 * (b.p - a.p) or LOCATE_TOL * self.width
        for k in range(3 * LOCATE_ITERATIONS):
            p = outside[-1][0] + step if k == 0 else self.outside_root(outside, inside, self.width)
            try:
                trial = self.first(outside[-1][2].x, p, 1.0)
            except FloatingPointError:   # no orbit found there: come back
                inside = p
                continue
            f = test(trial)
            if f is None or f <= 0:
                inside = p
                continue
            moved = abs(p - outside[-1][0]) / self.width
            outside.append((p, f, trial))
            if k > 0 and moved < LOCATE_TOL:   # (the first probe's step is no measure of convergence)
                break
        return outside[-1][2]

    @staticmethod
    def outside_root(outside, inside, width) -> float:
        """The root of the polynomial through the last three (or two) points (p, gap)
        nearest the last of them, within the bracket it makes with `inside` (else the
        bracket's midpoint) or, without one, within a tenth of the range of it."""
        near = outside[-1][0]
        points = outside[-3:]
        s, f = np.array([p[0] for p in points]), np.array([p[1] for p in points])
        roots = np.roots(np.polyfit(s - near, f, len(points) - 1)) + near
        real = [r.real for r in roots if abs(r.imag) < 1e-12 * max(1.0, abs(r))]
        if inside is not None:
            kept = [r for r in real if min(near, inside) < r < max(near, inside)]
            return min(kept, key=lambda r: abs(r - near)) if kept else 0.5 * (near + inside)
        if not real:
            return near
        root = min(real, key=lambda r: abs(r - near))
        return near + max(-0.1 * width, min(0.1 * width, root - near))

    def trial(self, a: Point, s: float) -> Point | None:
        """The branch point at arclength s from a (corrected), or None."""
        found = self.correct(a, s)
        if found is None:
            return None
        x, p, _, _ = found
        return oriented(a, self.point(x, p, a.tangent))

    def arclength(self, a: Point, b: Point) -> float:
        """b's distance from a along a's tangent (the corrector's constraint)."""
        return float(a.tangent @ (np.append(b.x, self.q(b.p)) - np.append(a.x, self.q(a.p))))


def null_vector(jac: np.ndarray) -> np.ndarray:
    """The unit null vector of an n x (n + 1) matrix (the last right singular vector)."""
    return np.linalg.svd(jac)[2][-1]


def _product(factors) -> float:
    """The real part of a product of factors that pair into conjugates (real, up to
    rounding)."""
    return float(np.real(np.prod(factors)))


def changes(fa, fb) -> bool:
    """A test function changes sign between two points: both values finite and of opposite
    signs, or the second exactly zero (a zero at a point belongs to the step that reached
    it, not to the next one)."""
    if fa is None or fb is None or not (math.isfinite(fa) and math.isfinite(fb)):
        return False
    return fa * fb < 0 or (fb == 0 and fa != 0)


def oriented(a: Point, b: Point) -> Point:
    """b with its tangent turned where its orientation flipped against a's: t_q is det(P_x - I)
    times the orientation (the null vector's last cofactor), so a t_q that changes sign where
    det(P_x - I) does not (no multiplier passed +1: no fold) is the orientation flipping (a
    secant that crossed the branch's turn, or noise in P_q), which would send the branch back
    over its own orbits and report a fold that is not there."""
    if changes(TESTS["fold"](a), TESTS["fold"](b)) and not changes(TESTS["branch_point"](a),
                                                                   TESTS["branch_point"](b)):
        b.tangent = -b.tangent
    return b


def grazes(a: Point, b: Point) -> bool:
    """The orbit's smallest gap to contact changes sign between a and b."""
    return changes(TESTS["grazing"](a), TESTS["grazing"](b))


def crossings(pt: Point) -> tuple[int, int, int]:
    """The real multipliers beyond -1 and beyond +1, and the complex pairs outside the unit
    circle: what a bifurcation changes by one."""
    real = [m.real for m in pt.multipliers if _real(m)]
    return sum(1 for m in real if m < -1), sum(1 for m in real if m > 1), _outside_complex(pt) // 2


def paired(a: Point, b: Point) -> bool:
    """Two multipliers crossed -1 or +1, or two complex pairs the unit circle, between a and
    b: their test functions' product does not change sign, so no single step may hold
    them. (A complex pair that meets on the real axis outside the circle moves between the
    counts but leaves as many multipliers outside: that is no crossing.)"""
    (n_a, p_a, c_a), (n_b, p_b, c_b) = crossings(a), crossings(b)
    outside = (n_b + p_b + 2 * c_b) - (n_a + p_a + 2 * c_a)
    return outside != 0 and max(abs(n_b - n_a), abs(p_b - p_a), abs(c_b - c_a)) > 1


def _real(m) -> bool:
    return abs(m.imag) <= REAL * max(1.0, abs(m))


def _outside_complex(pt) -> int:
    return int(sum(1 for m in pt.multipliers if not _real(m) and abs(m) > 1))


def _pairs(mu) -> np.ndarray:
    i, j = np.triu_indices(mu.size, 1)
    return mu[i] * mu[j] - 1.0


REAL = 1e-9               # |Im mu| below which a multiplier is real
TESTS = {
    "fold": lambda pt: float(pt.tangent[-1]),
    "branch_point": lambda pt: _product(pt.multipliers - 1.0),
    "period_doubling": lambda pt: _product(pt.multipliers + 1.0),
    "neimark_sacker": lambda pt: _product(_pairs(pt.multipliers)),
    "grazing": lambda pt: pt.measures.get("gap"),
}
