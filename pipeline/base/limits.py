"""The largest inputs a study may ask for, and the plausible range of every
number it gives, each with the reason, in one place.

A study beyond a limit is refused while it is read (within a second), with the
limit and the reason in the message, instead of filling the memory or the disk
hours later; a number out of its range (a length of 1e300 mm, a gear ratio of
1e300) is refused the same way instead of giving nonsense with status OK.
"""

# positions per revolution (scene tables, dense curves, sweeps): 0.0036 deg steps;
# a scene stores about 1 KiB per position and point set, a sweep worker holds
# (positions x 8 lanes x 40) floats
MAX_POSITIONS = 100_000
POSITIONS_WHY = "a 0.0036 deg step; more only fills the memory"

# candidates of one sweep: every candidate is a row of about 200 bytes in the
# results file and as much in the journal
MAX_CANDIDATES = 1_000_000_000
CANDIDATES_WHY = "about 200 GB of results; split a larger study by seed"

# candidates per chunk: two chunks are in memory at once, about 500 bytes each
MAX_CHUNK = 1_000_000
CHUNK_WHY = "two chunks are held in memory at once"

# designs per generation of an adaptive search (population and offspring): pymoo
# compares every proposed design with every design of the population (its duplicate
# elimination): a 5,000 population takes 0.45 GB more than a 100 one, 10,000 about 2 GB
MAX_POPULATION = 10_000
POPULATION_WHY = ("pymoo holds the distances between the proposed designs and the "
                  "population: about 2 GB at 10,000")


# ----------------------------------------------------------------- study files and names
# bytes of a study file: a study is stored verbatim in every results file (its root
# attributes, and so in every copy and export of it) and re-read by show and report; the
# largest shipped study is 5 kB, a table law of MAX_TABLE_POINTS points about 200 kB
MAX_STUDY_BYTES = 1_000_000
STUDY_BYTES_WHY = ("a study is stored verbatim in every results file; the largest shipped "
                   "one is 5 kB")

# characters of a name (a point, group, body, input, slide's body, dynamics case, sweep
# variable, the study's name): a name labels table columns, pictures and messages; 64
# characters hold any name a designer writes and keep every message on one line
MAX_NAME_LENGTH = 64
NAME_WHY = "a name labels columns, pictures and messages"

# characters of the study's title (a line of text above the pictures and the report)
MAX_TITLE_LENGTH = 200
TITLE_WHY = "the title is one line above the pictures and the report"

# points of an input's table law: its periodic spline is a constant of the generated
# kernel module (its knots and four coefficients per point, about 100 bytes of source:
# 10,000 points are 1 MB and 12,700 lines, 10^6 points a 5.5 GB compile); a cam is
# tabulated at a few hundred points
MAX_TABLE_POINTS = 10_000
TABLE_POINTS_WHY = ("the spline is written into the generated kernel module: 10,000 points "
                    "are about 1 MB of source")


# ----------------------------------------------------------------- ranges of the numbers
class Range:
    """The plausible values of one kind of number in a study: [low, high] in
    the study file's units (``low_open``: low itself excluded), with the
    reason.  Checked where the number is read (``pipeline.study.section.Section``)
    and against a sweep variable's bounds (``pipeline.study.sweep_spec``)."""

    def __init__(self, what, low, high, unit, why, low_open=False):
        self.what, self.low, self.high, self.unit = what, low, high, unit
        self.why, self.low_open = why, low_open

    def holds(self, v) -> bool:
        return (v > self.low if self.low_open else v >= self.low) and v <= self.high

    def words(self) -> str:
        lo = f"{'more than ' if self.low_open else ''}{self.low:,g}"
        unit = f" {self.unit}" if self.unit else ""
        return f"{self.what} is {lo} to {self.high:,g}{unit} ({self.why})"


# mm: the linkages of knitting and sewing machines (DOMAIN.md) have links of a few mm to
# about 1 m; 10 m leaves a factor ten, and anything beyond is a slip of units or of an
# exponent (1e300).  A length of at least 1 um: below it a link is a manufacturing
# tolerance, and the kernels square lengths (1e-300 ** 2 is 0)
MAX_LENGTH = 1e4
MIN_LENGTH = 1e-3
LENGTH = Range("a length", MIN_LENGTH, MAX_LENGTH, "mm",
               "10 m: ten times the largest linkage of these machines")
# coordinates, offsets, a slider's start and stroke, the centre of mass's distance: signed
OFFSET = Range("a coordinate or an offset", -MAX_LENGTH, MAX_LENGTH, "mm",
               "10 m: ten times the largest linkage of these machines")

# deg: an angle counts modulo a turn; ten turns either way leave room for every way of
# writing one (0..360, -180..180, a start angle unwound over several turns) and catch an
# exponent's slip (the sine of 1e300 rad is noise: its rounding exceeds a turn)
MAX_ANGLE = 3600.0
ANGLE = Range("an angle", -MAX_ANGLE, MAX_ANGLE, "deg", "ten turns either way")

# a geared crank's turns per cycle (a linear law's ratio): gear trains of these machines
# are 1:1 to about 1:10; 100 leaves a factor ten (the law must also be resolved by the
# positions, see LAW_MIN_POSITIONS)
MAX_RATIO = 100.0
RATIO = Range("a gear ratio", -MAX_RATIO, MAX_RATIO, "", "turns of the geared crank per "
              "cycle; these machines gear 1:1 to 1:10")

# rad/s: knitting machines run at about 1,000 rpm (105 rad/s), sewing machines up to about
# 10,000 rpm (1,050 rad/s); 10^4 rad/s (95,000 rpm) leaves a factor ten
MAX_OMEGA = 1e4
OMEGA = Range("an angular speed", -MAX_OMEGA, MAX_OMEGA, "rad/s",
              "95,000 rpm: ten times the fastest sewing machine")
# rad/s²: 1,000 rpm from rest in a tenth of a second is 10^3 rad/s²
MAX_EPS = 1e6
EPS = Range("an angular acceleration", -MAX_EPS, MAX_EPS, "rad/s²",
            "a thousand times a main shaft reaching 1,000 rpm in 0.1 s")

# kg: links weigh grams to a few kilograms; a ton is a slip of units (g for kg)
MAX_MASS = 1e3
MASS = Range("a mass", 0.0, MAX_MASS, "kg", "a ton: links weigh grams to kilograms",
             low_open=True)
# kg·m²: the largest mass at the largest length (MAX_MASS * (MAX_LENGTH / 1000)^2)
MAX_INERTIA = MAX_MASS * (MAX_LENGTH / 1000.0) ** 2
INERTIA = Range("a moment of inertia", 0.0, MAX_INERTIA, "kg·m²",
                "the largest mass at the largest length")

# m/s²: zero (a study without gravity) to ten times the Earth's
GRAVITY = Range("gravity", -100.0, 100.0, "m/s²", "ten times the Earth's")

# MPa: the allowable bending stress of a pin; the strongest steels allow about 2,000
STRESS = Range("an allowable stress", 0.0, 1e4, "MPa",
               "five times the strongest steels", low_open=True)

# Coulomb friction coefficients ([mechanism.friction]): lubricated steel on bronze about
# 0.05-0.1, dry steel on steel about 0.6; a coefficient of 2 is a slip (a percentage)
FRICTION = Range("a friction coefficient", 0.0, 2.0, "",
                 "dry steel on steel is about 0.6; more is a slip of units")
# MPa: the allowed pressure of a plain bearing (sintered bronze about 10-15, hardened steel
# on bronze about 25-60)
PRESSURE = Range("a bearing pressure", 0.0, 1e4, "MPa", "five times the strongest steels",
                 low_open=True)
# MPa*m/s: the allowed p*v of a plain bearing (bronze bushings about 1.5-3; PTFE composites
# to about 3.5)
PV = Range("a p*v limit", 0.0, 1e3, "MPa·m/s", "a hundred times the best plain bearings",
           low_open=True)
# mm: a slider's length along its guide (0: no length given, the couple carried without
# edge loads)
BLOCK_LENGTH = Range("a block length", 0.0, MAX_LENGTH, "mm",
                     "10 m: ten times the largest linkage of these machines")

# N·m·s: the crank's viscous damping (a motor's torque of tens of N·m over 100 rad/s is
# about 0.1 N·m·s)
DAMPING = Range("a damping coefficient", 0.0, 1e4, "N·m·s",
                "10^5 times a motor's torque per speed")

# s: a dynamics case's duration and steps: a run-up of the main shaft lasts seconds
DURATION = Range("a duration", 0.0, 3600.0, "s", "an hour of machine time", low_open=True)

# the values of a required motion law ([output.motion_law] values): normalised to their
# swing, in any unit of angle or length
LAW_VALUE = Range("a value of the motion law", -1e6, 1e6, "",
                  "any unit of angle or length; the law is normalised to its swing")

# seconds of a dynamics case, its RK4 steps (t_end / dt) and its samples (t_end /
# sample_dt): the shipped take-up study integrates 10 s in 10^5 steps and keeps 10^3
# samples
MAX_DYNAMICS_STEPS = 100_000_000
DYNAMICS_STEPS_WHY = "a thousand times the shipped take-up study's 10^5 steps"
MAX_DYNAMICS_SAMPLES = 1_000_000
DYNAMICS_SAMPLES_WHY = "every sample is a row of the results file and of its pictures"

# an input law must be resolved by the crank positions that sample it (the scene's dense
# revolution, a sweep's positions): a rise or return (harmonic, cycloidal) spans at least
# this many position steps, a geared crank (linear law) makes at most one turn per this
# many steps; the dense curves (tables, pictures, a sweep's metrics) then show the law's
# swing.  A table law's spline pieces each span at least TABLE_LAW_MIN_POSITIONS steps (its
# acceleration is linear on a piece: every piece is sampled).  The scene's refined peaks
# (pipeline.solve.peaks) divide the steps further round such a law and search each of its
# pieces apart: exact to 1e-6 at these limits (tests/solve/test_law_peaks.py)
LAW_MIN_POSITIONS = 8
TABLE_LAW_MIN_POSITIONS = 2
LAW_POSITIONS_WHY = ("a law steeper than the positions sample it passes between them "
                     "unseen: its peaks would be wrong")
