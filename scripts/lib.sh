# Shared by the bash scripts of scripts/ (sourced, never run): their --help, the checks of their arguments, the tincull
# binary they run and the Python environments they create. A script sources it from its own folder with shell builtins
# only (`source "$(cd -- "${BASH_SOURCE[0]%/*}" 2>/dev/null && pwd || pwd)/lib.sh"`: the folder of its path, or the
# current one when it was run by its bare name), so that --help and argument errors work with nothing but bash on the
# PATH.

# Prints the header comment of the script file $1: its --help.
usage_of() {
    awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$1"
}

# The arguments of a script that takes none ($1: the script's path, then its arguments): --help prints its header
# and exits, anything else is refused with exit 2.
takes_no_arguments() {
    local script=$1
    shift
    if [ $# -eq 1 ] && { [ "$1" = --help ] || [ "$1" = -h ]; }; then
        usage_of "$script"
        exit 0
    elif [ $# -gt 0 ]; then
        echo "scripts/${script##*/}: unknown argument $1 (it takes none; --help says what it does)" >&2
        exit 2
    fi
}

# The arguments of a script that takes one optional working directory ($1: the script's path, then its arguments):
# --help prints its header and exits; sets `work` to the directory made absolute (a new temporary directory when
# none is given, removed when the script exits, however it ends); refuses a flag or a second argument with exit 2.
optional_workdir() {
    local script=$1
    shift
    case "${1:-}" in
        -h | --help) usage_of "$script"; exit 0 ;;
        -*)
            echo "scripts/${script##*/}: unknown argument $1 (it takes an optional WORKDIR; --help says more)" >&2
            exit 2
            ;;
    esac
    if [ $# -gt 1 ]; then
        echo "scripts/${script##*/}: unknown argument $2 (it takes one optional WORKDIR; --help says what it does)" >&2
        exit 2
    fi
    if [ $# -eq 1 ]; then
        work=$(absolute "$1")
    else
        work=$(mktemp -d)
        trap 'rm -rf "$work"' EXIT
    fi
}

# Exits 2 with a message unless the flag $2 of the script $1 has a value ($3: how many arguments remain, the flag's
# included).
need_value() {
    if [ "$3" -lt 2 ]; then
        echo "scripts/$1: $2 needs a value" >&2
        exit 2
    fi
}

# Exits 2 with a message unless $2 is a whole number (the script $1's flag $3 took it).
need_whole_number() {
    if ! [[ "$2" =~ ^[0-9]+$ ]]; then
        echo "scripts/$1: $3 takes a whole number, not '$2'" >&2
        exit 2
    fi
}

# As need_whole_number, and exits 2 when it is 0 ($4, if given, says why 0 is refused).
need_count() {
    need_whole_number "$1" "$2" "$3"
    if [[ "$2" =~ ^0+$ ]]; then
        echo "scripts/$1: $3 must be at least 1${4:+ ($4)}" >&2
        exit 2
    fi
}

# Prints the path $1 made absolute against the current directory: call it before the script changes directory, so
# that paths are taken where the user typed them.
absolute() {
    case "$1" in
        /*) printf '%s\n' "$1" ;;
        *) printf '%s\n' "$PWD/$1" ;;
    esac
}

# Sets `bin` to the tincull binary for the script $1, run from the checkout's root: $TINCULL_BIN when it is set (a
# binary built beforehand: a copy keeps a long run independent of rebuilds meanwhile; a relative path is taken from
# where the script was started), else a release build of the checkout (`CARGO_TARGET_DIR` honoured). Exits 2 when
# that is not an executable file.
tincull_bin() {
    if [ -n "${TINCULL_BIN:-}" ]; then
        bin="$TINCULL_BIN"
    else
        echo "== building the release CLI" >&2
        cargo build --release --locked -p tincull --quiet
        bin=$(absolute "${CARGO_TARGET_DIR:-target}/release/tincull")
    fi
    if [ ! -f "$bin" ] || [ ! -x "$bin" ]; then
        echo "scripts/$1: $bin is not an executable tincull binary (TINCULL_BIN names one built beforehand)" >&2
        exit 2
    fi
}

# Creates the Python virtual environment $1 with the packages of the requirements file $2 when it is missing, when
# the requirements changed since it was made, or when an earlier install failed before writing its stamp (needs
# python3 with venv and pip).
python_env() {
    if [ ! -x "$1/bin/python" ] || ! cmp -s "$2" "$1/.requirements"; then
        echo "== creating $1" >&2
        rm -rf "$1"
        python3 -m venv "$1"
        "$1/bin/python" -m pip install --quiet --disable-pip-version-check -r "$2"
        cp "$2" "$1/.requirements"
    fi
}

# Taken where the script was started, before it changes directory.
if [ -n "${TINCULL_BIN:-}" ]; then
    TINCULL_BIN=$(absolute "$TINCULL_BIN")
fi
