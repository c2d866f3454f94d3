"""The command line shared by the chart scripts (`scripts/*_chart.py`): checked before anything is read or drawn, so
that `--help` never redraws a chart and a missing matplotlib is named instead of a traceback."""
import sys


def pyplot(doc, usage="", max_args=0):
    """Prints `doc` and exits for `-h`/`--help`; exits naming the first argument beyond `max_args` (the script's
    `usage` in the message); exits naming the interpreter when matplotlib is missing. Returns `matplotlib.pyplot`,
    drawing without a display (Agg)."""
    name = sys.argv[0]
    if any(a in ("-h", "--help") for a in sys.argv[1:]):
        print(doc.strip())
        sys.exit(0)
    if len(sys.argv) > 1 + max_args:
        sys.exit(f"{name}: unknown argument {sys.argv[1 + max_args]} (usage: {name}{usage}; --help says more)")
    try:
        import matplotlib
    except ImportError as e:
        sys.exit(
            f"error: matplotlib is not installed for {sys.executable} ({e}): scripts/charts makes .venv-notebooks "
            "with it; run this with .venv-notebooks/bin/python"
        )
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt
