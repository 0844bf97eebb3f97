"""The README's Python example runs as written."""

import re


def test_readme_python_example(repo, capsys):
    text = (repo / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks, "the README has a Python example"
    for block in blocks:
        exec(compile(block, "README.md", "exec"), {})
    assert capsys.readouterr().out.count("\n") >= 2


def run_examples(text, path):
    """Run the `>>>` examples of a page; the doctest results (failed, attempted)."""
    import doctest

    test = doctest.DocTestParser().get_doctest(text, {}, "python.md", str(path), 0)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    runner.run(test, out=lambda _: None)
    return runner.summarize(verbose=False)


def test_python_guide_examples(repo, capsys):
    """Every `>>>` example of docs/guide/python.md runs and prints what the page quotes, at
    the printed digits: a number that drifts from what the code produces fails here."""
    import doctest

    path = repo / "docs" / "guide" / "python.md"
    text = path.read_text(encoding="utf-8")
    test = doctest.DocTestParser().get_doctest(text, {}, "python.md", str(path), 0)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.attempted >= 20, "the guide's examples are found"
    assert result.failed == 0, f"{result.failed} of the guide's examples print something else"


def test_python_guide_check_sees_a_drifted_number(repo):
    """Negative control: the first section with the symplecticity defect the guide once
    quoted (1.93e-11, before the velocity form's fixed-point start; 1.35e-11 before the
    guesses' residuals were rounded; the run prints 1.29e-11)
    fails, the section as written passes."""
    path = repo / "docs" / "guide" / "python.md"
    text = path.read_text(encoding="utf-8")
    first = text[: text.index("## Running scenes")]
    assert "\n1.29e-11\n" in first
    assert run_examples(first, path).failed == 0
    drifted = first.replace("\n1.29e-11\n", "\n1.93e-11\n")
    assert run_examples(drifted, path).failed == 1


def test_python_guide_sweep_counts_are_the_scripts(repo):
    """The guide's counts of the bad-input sweep are the script's lists (the sweep itself runs
    each case in its own interpreter, minutes, outside the suite)."""
    import runpy

    sweep = runpy.run_path(str(repo / "scripts" / "bad_input_sweep_python.py"), run_name="sweep")
    bad, long = len(sweep["BAD"]), len(sweep["CTRL_C"])
    text = (repo / "docs" / "guide" / "python.md").read_text(encoding="utf-8")
    assert f"runs {bad} bad calls" in text
    assert f"and {long} long calls" in text
    assert f"cases tried: {bad + long};" in text
