"""Problems the success gates must refuse, shared by several test modules."""

#: a robot whose steady cycle passes a snap-through under physical gravity: the equilibrium jumps at
#: phase 0.0975 (no continuous branch; across the jump the energy balance misses 4.4 % of the work)
SNAP_THROUGH = {"robot": {"M": 0.41225071115315814, "L": 0.12975204385746983,
                          "beta": 0.613461927615284,
                          "k": 0.018389935602215093, "g": 9.81, "mu1": 0.9486174109066826,
                          "mu2": 0.07199087717290628},
                "gait": {"drive": "torque", "psi_deg": -274.5634823796951,
                         "gamma_deg": 118.31006032658763,
                         "A_deg": 23.534673118354448}, "model": {"gravity": "physical"}}
