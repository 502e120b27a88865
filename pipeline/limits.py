"""The largest inputs a study may ask for, each with the reason, in one place.

A study beyond a limit is refused while it is read (within a second), with the
limit and the reason in the message, instead of filling the memory or the disk
hours later.
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
