"""The rows of the bad-input matrix (tests/test_bad_input.py) for data files and waveforms: fit's
measurement files and parameters, and the non-harmonic gait waveforms with their sample tables."""
from _bad_input_rows import CHAIN_TEXT, PAPER_TEXT, REPO, R

# ---- fit: measurement files (the CSV convention) and parameters
_FIT_HEAD = b"A [deg],S [mm],sigma_S [mm]\n"
_FIT_ROWS = b"15,-27.7,0.2\n22,-41.1,0.2\n30,-56.0,0.2\n"


def _fit(words, *extra, data=_FIT_HEAD + _FIT_ROWS, params=("robot.k",)):
    argv = ["{paper}", "{tmp}/d.csv", *(a for p in params for a in ("--param", p)), "--out",
            "{tmp}/out", *extra]
    return R("fit", argv, words, files={"d.csv": data})


DATA_ROWS = {
    "fit: NaN measurement": _fit(["d.csv:3", "'S [mm]'", "not a finite number"],
                                 data=_FIT_HEAD + b"15,-27.7,0.2\n22,nan,0.2\n30,-56.0,0.2\n"),
    "fit: too few points":
        _fit(["d.csv", "too few points", "2 parameter(s)"], params=("robot.k", "robot.mu"),
             data=_FIT_HEAD + b"15,-27.7,0.2\n22,-41.1,0.2\n"),
    "fit: unknown parameter":
        _fit(["--param robot.kk", "unknown parameter", "did you mean robot.k?"],
             params=("robot.kk",)),
    "fit: zero uncertainty": _fit(["d.csv:4", "sigma_S", "must be > 0"],
                                  data=_FIT_HEAD + b"15,-27.7,0.2\n22,-41.1,0.2\n30,-56.0,0\n"),
    "fit: negative uncertainty":
        _fit(["d.csv:2", "sigma_S", "must be > 0"],
             data=_FIT_HEAD + b"15,-27.7,-0.2\n22,-41.1,0.2\n30,-56.0,0.2\n"),
    "fit: unit mismatch": _fit(["d.csv:1", "'S'", "[deg] is not a length unit"],
                               data=b"A [deg],S [deg],sigma_S [mm]\n" + _FIT_ROWS),
    "fit: no uncertainty column":
        _fit(["d.csv", "missing column 'sigma_S'"], data=b"A [deg],S [mm]\n15,-27.7\n22,-4\n"),
    "fit: start outside the bounds":
        _fit(["--param robot.k", "within bounds"], "--bounds", "robot.k=0.2:0.3"),
    "fit: --max-nfev 0": _fit(["--max-nfev 0", "in [1, 10000]"], "--max-nfev", "0"),
    "fit: --starts -1": _fit(["--starts -1", "in [0, 10000]"], "--starts", "-1"),
    "fit: rows x evaluations, hours":
        _fit(["20000 rows x 10000 evaluations", "DATA.csv rows", "--max-nfev"],
             "--max-nfev", "10000",
             data=_FIT_HEAD + b"".join(b"%.6f,-30.0,0.2\n" % (15 + j * 1e-4)
                                       for j in range(20000))),
    "fit: unknown pressure constant":
        _fit(["--pressure pressure.c1", "unknown pressure constant"], "--pressure",
             "pressure.c1=0.1"),
}
_CHAIN_FIT = ["{file}", "{tmp}/d.csv", "--param", "robot.stiffness[0]", "--out", "{tmp}/out"]
_PRESSURE_ROWS = (b"psi [deg],p0 [bar],S_norm [-],sigma_S_norm [-]\n10,1.7,1,0.1\n45,1.7,0.9,0.1\n"
                  b"90,1.7,0.7,0.1\n")
DATA_ROWS.update({
    "fit: stiffness rows on a chain":
        R("fit", _CHAIN_FIT, ["d.csv", "stiffness rows", "chain", "robot.stiffness[j]"],
          text=CHAIN_TEXT, files={"d.csv": b"tau [N m],phi [deg],sigma_phi [deg]\n"
                                           b"0.01,3,0.1\n0.02,6,0.1\n0.03,9,0.1\n"}),
    "fit: pressure rows on a chain of five links":
        R("fit", _CHAIN_FIT, ["d.csv:2", 'waveform = "pressure"', "chain of 5 links"],
          text=CHAIN_TEXT, files={"d.csv": _PRESSURE_ROWS}),
    "fit: the joints' segments as a parameter":
        R("fit", ["{tmp}/five.toml", "{tmp}/d.csv", "--param", "pressure.segments[0]", "--out",
                  "{tmp}/out"], ["--param pressure.segments[0]", "unknown parameter"],
          files={"d.csv": _PRESSURE_ROWS,
                 "five.toml": (REPO / "problems" / "pressure_robot_five_links.toml").read_bytes()}),
    "fit: an entry past a chain's array":
        R("fit", [*_CHAIN_FIT, "--param", "robot.stiffness[4]"],
          ["--param robot.stiffness[4]", "unknown parameter", "robot.stiffness[3]"],
          text=CHAIN_TEXT, files={"d.csv": _PRESSURE_ROWS}),
})
DATA_ROWS["fit: earlier results"] = R("fit",
                                      ["{paper}", "{tmp}/d.csv", "--param", "robot.k", "--out",
                                       "{tmp}/out"],
                                      ["--out", "would overwrite", "--force"],
                                      files={"d.csv": _FIT_HEAD + _FIT_ROWS, "out/fit.json": b"{}"})


def gait(lines: str) -> str:
    """The paper problem with its [gait] section's keys replaced by ``lines`` (drive kept)."""
    start = PAPER_TEXT.index("gamma_deg = 90.0")
    return PAPER_TEXT[:start] + lines + "\n\n" + PAPER_TEXT[PAPER_TEXT.index("[model]"):]


#: a table of torques over one cycle (the optimize convention) and rows to break it with
CSV_HEAD = "phase [-],tau1 [N m],tau2 [N m]\n"
CSV_ROWS = "0.0,-0.29,-0.29\n0.25,-0.25,-0.33\n0.5,-0.29,-0.29\n0.75,-0.33,-0.25\n"
SAMPLES = 'waveform = "samples"\nfile = "work/t.csv"'


def csv(text: str) -> dict:
    return {"t.csv": text.encode()}


#: non-harmonic waveforms ([gait] waveform) are validated like every other key; files name their
#: line
DATA_ROWS.update({
    "simulate: unknown waveform":
        R("simulate", ["{file}"], ["x.toml", '[gait] waveform = "square"', '"pulse"'],
          text=gait('waveform = "square"')),
    "simulate: harmonic key with samples":
        R("simulate", ["{file}"],
          ["x.toml", "[gait] gamma_deg = 90.0", 'waveform = "samples"',
           'key of waveform = "harmonic"'],
          text=gait(SAMPLES + "\ngamma_deg = 90.0"), files=csv(CSV_HEAD + CSV_ROWS)),
    "simulate: samples file missing":
        R("simulate", ["{file}"], ["x.toml", "[gait] file", "nope.csv", "No such file"],
          text=gait('waveform = "samples"\nfile = "nope.csv"')),
    "simulate: --input missing":
        R("simulate", ["{paper}", "--input", "{tmp}/nope.csv"],
          ["paper_gait.toml", "[gait] file", "nope.csv", "(from --set)", "No such file"]),
    "simulate: samples not periodic":
        R("simulate", ["{file}"], ["x.toml", "[gait] file", "t.csv:6", "not periodic"],
          text=gait(SAMPLES), files=csv(CSV_HEAD + CSV_ROWS + "1.0,-0.3,-0.29\n")),
    "simulate: too many samples":
        R("simulate", ["{file}"],
          ["x.toml", "[gait] file", "10001 samples in one period, at most 10000"],
          text=gait(SAMPLES),
          files=csv(CSV_HEAD + "".join(f"{j / 10001!r},-0.29,-0.29\n"
                                       for j in range(10001)))),
    "simulate: samples NaN":
        R("simulate", ["{file}"], ["x.toml", "[gait] file", "t.csv:3", "'tau1 [N m]'",
                                   "not a finite number"],
          text=gait(SAMPLES), files=csv(CSV_HEAD + CSV_ROWS.replace("-0.25,", "nan,", 1))),
    "simulate: samples NaN inline":
        R("simulate", ["{file}"], ["x.toml", "[gait] tau1 = [0.1, nan", "entry 1 = nan",
                                   "finite"],
          text=gait('waveform = "samples"\nphase = [0, 0.5, 0.7]\ntau1 = [0.1, nan, 0.1]\n'
                    'tau2 = [0.1, 0.2, 0.1]')),
    "simulate: samples unknown column":
        R("simulate", ["{file}"], ["x.toml", "t.csv:1", "unknown column(s) 'tau3'"],
          text=gait(SAMPLES),
          files=csv("phase [-],tau1 [N m],tau3 [N m]\n" + CSV_ROWS)),
    "simulate: samples one torque column":
        R("simulate", ["{file}"], ["x.toml", "t.csv", "'tau2 [N m]'", "header has"],
          text=gait(SAMPLES),
          files=csv("phase [-],tau1 [N m]\n0.0,0.1\n0.5,0.2\n0.7,0.1\n")),
    "simulate: samples wrong unit":
        R("simulate", ["{file}"], ["x.toml", "t.csv:1", "[deg] is not a torque unit"],
          text=gait(SAMPLES), files=csv(CSV_HEAD.replace("tau1 [N m]", "tau1 [deg]") +
                                        CSV_ROWS)),
    "simulate: samples unsorted":
        R("simulate", ["{file}"], ["x.toml", "t.csv:4", "phase 0.2 after 0.25",
                                   "sorted and unique"],
          text=gait(SAMPLES), files=csv(CSV_HEAD + CSV_ROWS.replace("0.5,", "0.2,", 1))),
    "simulate: samples repeated phase inline":
        R("simulate", ["{file}"], ["x.toml", "[gait] phase", "entry 2",
                                   "sorted and unique"],
          text=gait('waveform = "samples"\nphase = [0, 0.5, 0.5]\n'
                    'tau1 = [0.1, 0.2, 0.1]\ntau2 = [0.1, 0.2, 0.1]')),
    "simulate: samples angle outside the geometry":
        R("simulate", ["{file}"],
          ["x.toml", "t.csv:3", "phi1_ref = 400.0 deg", "(0, 360)"],
          text=gait(SAMPLES), files=csv(
              "phase [-],phi1_ref [deg],phi2_ref [deg]\n0,90,90\n"
              "0.3,400,80\n0.6,90,100\n")),
    "simulate: samples foot off the ground":
        R("simulate", ["{file}"], ["x.toml", "[gait]", "foot 1 off the ground"],
          text=gait('waveform = "samples"\nphase = [0, 0.3, 0.6]\n'
                    'phi1_ref_deg = [41.5, 90, 90]\nphi2_ref_deg = [18.5, 90, 90]')),
    "simulate: samples lengths differ":
        R("simulate", ["{file}"], ["x.toml", "[gait] tau2", "2 entries where phase has 3"],
          text=gait('waveform = "samples"\nphase = [0, 0.3, 0.6]\n'
                    'tau1 = [0.1, 0.2, 0.1]\ntau2 = [0.1, 0.2]')),
    "simulate: torque samples, angles drive":
        R("simulate", ["{file}", "--drive", "angles"],
          ["x.toml", '[gait] drive = "angles"', "torque samples"],
          text=gait(SAMPLES), files=csv(CSV_HEAD + CSV_ROWS)),
    "simulate: pulse edges longer than the cycle":
        R("simulate", ["{file}"], ["x.toml", "[gait] rise = 0.4",
                                   "hold = 0.3", "<= 1"],
          text=gait('waveform = "pulse"\ngamma_deg = 90.0\nA_deg = 20.0\n'
                    'psi_deg = 90.0\nrise = 0.4\nhold = 0.3')),
    "simulate: pulse without rise":
        R("simulate", ["{file}"], ["x.toml", "[gait] rise is missing",
                                   'waveform = "pulse"'],
          text=gait('waveform = "pulse"\ngamma_deg = 90.0\nA_deg = 20.0\n'
                    'psi_deg = 90.0\nhold = 0.3')),
    "simulate: fourier of 101 harmonics":
        R("simulate", ["{file}"], ["x.toml", "[gait] cos1_deg", "at most 100"],
          text=gait('waveform = "fourier"\ngamma_deg = 90.0\ncos1_deg = [' +
                    ", ".join(["0.1"] * 101) + "]")),
    "simulate: fourier coefficient a string":
        R("simulate", ["{file}"], ["x.toml", "[gait] sin2_deg", "entry 0",
                                   "expected a number"],
          text=gait('waveform = "fourier"\ngamma_deg = 90.0\nsin2_deg = ["1"]')),
})


#: found by fuzzing the command line: internal errors and a read without end
DATA_ROWS.update({
    "simulate: empty inline samples (IndexError)":
        R("simulate", ["{file}"], ["x.toml", "[gait] phase = []",
                                  "no samples"],
          text=gait('waveform = "samples"\nphase = []\ntau1 = []\n'
                    'tau2 = []')),
    "simulate: NUL in the samples file name (ValueError)":
        R("simulate", ["{file}"],
          ["x.toml", "[gait] file", "invalid path"],
          text=gait('waveform = "samples"\nfile = "a\\u0000b.csv"')),
    "simulate: --input /dev/zero (read without end)":
        R("simulate", ["{paper}", "--input", "/dev/zero"],
          ["/dev/zero", "larger than 16 MiB"]),
    "simulate: samples cell 1_0 (read as 10)":
        R("simulate", ["{file}"], ["x.toml", "t.csv:3", "'1_0' is not a number"],
          text=gait(SAMPLES),
          files=csv(CSV_HEAD + CSV_ROWS.replace("-0.25,", "1_0,", 1))),
    "simulate: samples cell in Arabic-Indic digits":
        R("simulate", ["{file}"], ["x.toml", "t.csv:2", "is not a number"],
          text=gait(SAMPLES),
          files=csv(CSV_HEAD + "\u0660,-0.29,-0.29\n" + CSV_ROWS[16:])),
    "simulate: --input with --set gait.waveform":
        R("simulate", ["{paper}", "--input", "{tmp}/t.csv", "--set",
                      "gait.waveform=harmonic"],
          ["--input", "--set gait.waveform=harmonic", "give one"],
          files=csv(CSV_HEAD + CSV_ROWS)),
    "simulate: --input dropped by --set gait.phase":
        R("simulate", ["{paper}", "--input", "{tmp}/t.csv", "--set",
                     "gait.phase=[0, 0.3, 0.6]", "--set",
                     "gait.tau1=[0.1, 0.2, 0.1]", "--set",
                     "gait.tau2=[0.1, 0.2, 0.1]"],
          ["--input", "sets gait.file", "--set gait.phase=[0, 0.3, 0.6]",
           "give one"], files=csv(CSV_HEAD + CSV_ROWS)),
    "simulate: --input with a harmonic key (dropped)":
        R("simulate", ["{paper}", "--input", "{tmp}/t.csv", "--set",
                     "gait.psi_deg=10"],
         ["[gait] psi_deg = 10 (from --set)", 'waveform = "samples"'],
         files=csv(CSV_HEAD + CSV_ROWS)),
    "fit: empty measurement file (no example)":
        _fit(["d.csv", "no header row", "'S [m]'"], data=b""),
    "fit: operating point out of range (fit failed)":
        _fit(["d.csv:3", "psi = 900 deg", "gait.psi_deg"],
             data=b"psi [deg],S [mm],sigma_S [mm]\n0,-20,1\n900,-43,3\n"
                  b"45,-50,1\n"),
    "fit: a bound outside the valid range":
        _fit(["--bounds robot.k=-1:1", "low end -1"], "--bounds", "robot.k=-1:1"),
    "fit: foot off the ground at a row (fit failed)":
        _fit(["d.csv:3", "gamma = 30 deg", "off the ground"],
             data=b"gamma [deg],S [mm],sigma_S [mm]\n90,-20,1\n"
                  b"30,-43,3\n100,-50,1\n"),
})


#: found by a second round of fuzzing
DATA_ROWS.update({
    "simulate: sample phases one ulp apart (ValueError)":
        R("simulate", ["{file}"],
         ["t.csv:4", "at least 1e-09 cycles apart"],
         text=gait(SAMPLES), files=csv(
             CSV_HEAD + "0,-0.2,-0.26\n0.5,-0.3,-0.2\n"
             "0.5000000000000001,-0.26,-0.3\n")),
    "simulate: a subnormal sample phase (ValueError)":
        R("simulate", ["{file}"], ["[gait] phase", "entry 1",
                                  "at least 1e-09 cycles apart"],
         text=gait('waveform = "samples"\nphase = [0, 5e-324, 0.5]\n'
                   'tau1 = [0.1, 0.2, 0.1]\ntau2 = [0.1, 0.2, 0.1]\n'
                   'interpolation = "spline"')),
})


#: the period of a cycle ([gait] period, a sample file's period column) and the pressure waveform
_PERIODS = CSV_ROWS.replace("\n", ",2.5\n")
DATA_ROWS.update({
    "simulate: a period of 0 s":
        R("simulate", ["{paper}", "--set", "gait.period=0"],
          ["[gait] period = 0 (from --set)", "> 0", "duration of one cycle"]),
    "simulate: [gait] period against the file's period column": R(
        "simulate", ["{file}"],
        ["x.toml", "[gait] period = 2.0", "gives the period 2.5 s in its period column"],
        text=gait(SAMPLES + "\nperiod = 2.0"),
        files=csv(CSV_HEAD.replace("\n", ",period [s]\n") + _PERIODS)),
    "simulate: a period column of two periods": R(
        "simulate", ["{file}"], ["t.csv:4", "period 3.0 s differs from 2.5 s"], text=gait(SAMPLES),
        files=csv(CSV_HEAD.replace("\n", ",period [s]\n") + _PERIODS.replace("0.5,-0.29,-0.29,2.5",
                                                                             "0.5,-0.29,-0.29,3.0"))),
    "simulate: pressure waveform without p0_bar":
        R("simulate", ["{file}"],
          ["x.toml", "[gait] p0_bar is missing", 'waveform = "pressure"'],
          text=gait('waveform = "pressure"\npsi_deg = 45.0')),
    "simulate: pressure amplitude above p0":
        R("simulate", ["{file}"], ["x.toml", "[gait] p0_bar = 0.3",
                                   "amplitude_bar = 0.4", "at most p0"],
          text=gait('waveform = "pressure"\npsi_deg = 45.0\np0_bar = 0.3')),
    "fit: --form against the problem's [pressure] form":
        _fit(["--form paper", '[pressure] form = "raised"',
              "give one"], "--form", "paper",
             "--set", "pressure.form=raised"),
})
