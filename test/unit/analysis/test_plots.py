"""Tests of `uvms plot` (uvms_analysis.plots): the PNG files it writes."""

from __future__ import annotations

from pathlib import Path

import pytest
from uvms_analysis.plots import RECORDING_FIGURES, figure_force_response, figure_thrusters, main
from uvms_analysis.series import load_run

PNG_MAGIC = b'\x89PNG\r\n\x1a\n'


def png_size(path: Path) -> tuple[int, int]:
    """Width and height of a PNG, from its IHDR chunk."""
    data = path.read_bytes()
    assert data[:8] == PNG_MAGIC, f'{path} is not a PNG'
    return int.from_bytes(data[16:20], 'big'), int.from_bytes(data[20:24], 'big')


def test_plot_writes_every_recording_figure_and_prints_the_paths(
    capsys: pytest.CaptureFixture[str], contact_recording: Path, tmp_path: Path
) -> None:
    """A recording with every topic gives the five figures, each path printed once."""
    status = main([str(contact_recording), '--out', str(tmp_path / 'figs')])
    printed = capsys.readouterr().out.split()
    expected = [str(tmp_path / 'figs' / name) for name in RECORDING_FIGURES]
    assert status == 0
    assert printed == expected
    assert sorted(p.name for p in (tmp_path / 'figs').iterdir()) == sorted(RECORDING_FIGURES)


@pytest.fixture(scope='module')
def moving_wall_figures(
    moving_wall_recording: Path, tmp_path_factory: pytest.TempPathFactory
) -> Path:
    """Directory with the figures of the moving-wall run."""
    out = tmp_path_factory.mktemp('moving_wall_figs')
    assert main([str(moving_wall_recording), '--out', str(out)]) == 0
    return out


@pytest.mark.parametrize('name', list(RECORDING_FIGURES))
def test_recording_figure_is_a_png_of_legible_size(moving_wall_figures: Path, name: str) -> None:
    """Each figure is a real PNG at least 960 px wide and 600 px high (8 x 5 in at 120 dpi)."""
    width, height = png_size(moving_wall_figures / name)
    assert width >= 960 and height >= 600


def test_ground_truth_force_is_drawn_thin_over_the_wider_measured_force(
    contact_recording: Path,
) -> None:
    """Noise-free, the two forces coincide: the thin dashed truth on top leaves both visible."""
    fig = figure_force_response(load_run(contact_recording))
    assert fig is not None
    lines = {line.get_label(): line for line in fig.axes[0].get_lines()}
    measured = lines['$F_e$ measured (controller)']
    truth = lines['$F_e$ ground truth (simulator)']
    assert truth.get_zorder() > measured.get_zorder()
    assert truth.get_linewidth() < measured.get_linewidth() / 2
    assert truth.get_linestyle() == '--'


def test_thruster_lines_differ_in_style_where_symmetric_thrusters_overlap(
    contact_recording: Path,
) -> None:
    """Every thruster has its own marker and dash pattern, markers at staggered samples."""
    fig = figure_thrusters(load_run(contact_recording))
    assert fig is not None
    lines = [line for line in fig.axes[0].get_lines() if line.get_label().startswith('T')]
    assert len(lines) >= 8
    assert len({line.get_marker() for line in lines}) == len(lines)
    assert len({str(line._dash_pattern) for line in lines}) == len(lines)  # type: ignore[attr-defined]
    starts = [line.get_markevery()[0] for line in lines]  # type: ignore[index]
    assert len(set(starts)) == len(lines)


def test_figures_without_their_topics_are_skipped_with_a_note(
    capsys: pytest.CaptureFixture[str], free_motion_recording: Path, tmp_path: Path
) -> None:
    """A recording without thruster state gets no thrusters.png, and stderr says why."""
    status = main([str(free_motion_recording), '--out', str(tmp_path)])
    err = capsys.readouterr().err
    assert status == 0
    assert not (tmp_path / 'thrusters.png').exists()
    assert (tmp_path / 'force_response.png').exists()
    assert 'thrusters.png' in err and '/uvms/thrusters/state' in err


def test_output_directory_defaults_to_the_recording_path_without_suffix(
    capsys: pytest.CaptureFixture[str], contact_recording: Path, tmp_path: Path
) -> None:
    """`uvms plot out/run.mcap` writes into out/run/."""
    copy = tmp_path / 'run.mcap'
    copy.write_bytes(contact_recording.read_bytes())
    assert main([str(copy)]) == 0
    assert (tmp_path / 'run' / 'force_response.png').is_file()


def test_fuzzy_figures_are_written_from_the_controllers_switch(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """--fuzzy alone draws the membership functions (Fig. 4) and the surface (Fig. 5)."""
    status = main(['--fuzzy', '--out', str(tmp_path)])
    printed = capsys.readouterr().out.split()
    assert status == 0
    assert printed == [str(tmp_path / 'fuzzy_membership.png'), str(tmp_path / 'fuzzy_surface.png')]
    for path in printed:
        width, height = png_size(Path(path))
        assert width >= 960 and height >= 600


def test_plot_without_recording_or_fuzzy_is_a_usage_error(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """Nothing to draw: status 2 and a message."""
    assert main(['--out', str(tmp_path)]) == 2
    assert 'recording' in capsys.readouterr().err


def test_unreadable_recording_fails_with_a_message_and_no_traceback(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """A corrupt file gives status 1, a one-line error naming it, and no figures."""
    bad = tmp_path / 'broken.mcap'
    bad.write_bytes(b'not mcap')
    status = main([str(bad), '--out', str(tmp_path / 'figs')])
    err = capsys.readouterr().err
    assert status == 1
    assert 'broken.mcap' in err and 'Traceback' not in err
    assert not (tmp_path / 'figs').exists() or not any((tmp_path / 'figs').iterdir())
