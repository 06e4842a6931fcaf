"""``--help`` of every subcommand: no literal ``%%`` and no unwrapped paragraph (issue 46)."""

from __future__ import annotations

import pytest

from palpbayes.cli import SUBCOMMANDS, build_parser

#: Longest line a rendered help may have [characters] (at an 80-column terminal).
MAX_LINE = 100


def _helps() -> dict[str, str]:
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    return {"palpbayes": parser.format_help(),
            **{name: p.format_help() for name, p in sub.choices.items()}}


@pytest.fixture
def helps(monkeypatch):
    monkeypatch.setenv("COLUMNS", "80")
    return _helps()


def test_every_subcommand_is_rendered(helps):
    assert set(SUBCOMMANDS) <= set(helps)


@pytest.mark.parametrize("name", ["palpbayes", *SUBCOMMANDS])
def test_help_has_no_double_percent(helps, name):
    """``follow --help`` once showed "90 %%": a description written for %-formatting under
    RawDescriptionHelpFormatter, which does not format it."""
    assert "%%" not in helps[name], name


@pytest.mark.parametrize("name", ["palpbayes", *SUBCOMMANDS])
def test_help_has_no_overlong_line(helps, name):
    """... on one unwrapped line of 500 characters (RawDescriptionHelpFormatter keeps the
    description's lines as written: follow's is wrapped by textwrap now).  argparse wraps
    neither such a description nor an argument group's title: keep both short."""
    long = [ln for ln in helps[name].splitlines() if len(ln) > MAX_LINE]
    assert not long, (name, long)


def test_the_target_help_keeps_its_promise(helps):
    """The help of --target said "the budget interval is printed beside it" while follow
    printed none; now both commands print it and --target-on says which one is tested."""
    for name in ("follow", "replay"):
        text = " ".join(helps[name].split())
        assert "--target-on {full,stat}" in text
        assert "both intervals are printed" in text
        assert "the budget interval is printed beside it" not in text


#: The subcommands that take the trace's sign options (one argparse group, cli/options.py).
SIGNED = ("fit", "replay", "follow", "map")


@pytest.mark.parametrize("name", SIGNED)
def test_the_sign_options_show_and_take_1_and_minus_1(helps, capsys, name):
    """Issue 58, item 7: ``--force-sign {1.0,-1.0}`` in the help and "invalid choice: 2.0
    (choose from 1.0, -1.0)" in the error; now ``{1,-1}`` in both, and the value stays the
    float the readers take."""
    assert "--force-sign {1,-1}" in helps[name] and "--z-sign {1,-1}" in helps[name]
    assert "1.0" not in helps[name]
    parser = build_parser()
    head = {"fit": ["x.csv", "--out", "r"], "replay": ["x.csv"], "follow": [],
            "map": ["x.csv", "--out", "m"]}[name]
    args = parser.parse_args([name, *head, "--force-sign", "-1", "--z-sign", "+1"])
    assert (args.force_sign, args.z_sign) == (-1.0, 1.0) and isinstance(args.force_sign, float)
    argv = [name, *head, "--force-sign", "2"]
    with pytest.raises(SystemExit):
        parser.parse_args(argv)
    err = capsys.readouterr().err
    assert "argument --force-sign: invalid choice: '2' (choose from 1, -1)" in err
    assert "1.0" not in err
