"""The command line shared by the chart scripts (`scripts/*_chart.py`): checked before anything is read or drawn, so
that `--help` never redraws a chart and a missing matplotlib is named instead of a traceback."""
import sys


def pyplot(doc, usage="", max_args=0):
    """Prints `doc` and exits for `-h`/`--help`; exits with status 2 naming an option it does not know or the first
    argument beyond `max_args` (the script's `usage` in the message); exits naming the interpreter when matplotlib is
    missing. Returns `matplotlib.pyplot`,
    drawing without a display (Agg)."""
    name = sys.argv[0]
    if any(a in ("-h", "--help") for a in sys.argv[1:]):
        print(doc.strip())
        sys.exit(0)
    args = sys.argv[1:]
    unknown = next((a for a in args if a.startswith("-") and a != "-"), None)
    if unknown is None and len(args) > max_args:
        unknown = args[max_args]
    if unknown is not None:
        print(f"{name}: unknown argument {unknown} (usage: {name}{usage}; --help says more)", file=sys.stderr)
        sys.exit(2)
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
