"""What several test files share: a tiny film, a whitted scene without a max_depth default, writing
a file, and the check that a command failed in one sentence (exit 2, no traceback)."""

from __future__ import annotations

from pathlib import Path

from phonglab import cli

FILM = ('<sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 4" '
        'target="0, 0, 0" up="0, 1, 0"/></transform><film type="hdrfilm">'
        '<integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>')
WHITTED_NO_DEPTH_DEFAULT = f"""<scene version="3.0.0">
  <integrator type="whitted"><string name="units" value="graphics"/></integrator>
  {FILM}
  <shape type="sphere"><bsdf type="phong"/></shape>
  <emitter type="point"><point name="position" value="0, 2, 3"/><rgb name="intensity" value="5"/></emitter>
</scene>"""


def write(tmp_path: Path, name: str, text: str) -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def fails_in_one_sentence(capsys, argv: list[str], *patterns: str) -> str:
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.split("\r")[-1].strip()   # after the progress bar, if any
    assert err.startswith("phonglab: error: ") and "\n" not in err, err
    assert "Traceback" not in err and "malformed XML" not in err, err
    for p in patterns:
        assert p in err, (p, err)
    return err
