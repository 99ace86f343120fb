"""What ``uvms identify fit`` writes of the actuators: thrusters.yaml, robot.urdf, the report.

Where the robot folder holds them (docs/robots.md "Adding a robot"):

- **Thrusters' lag**: ``thrusters.yaml`` models the T200 (Healey et al. 1995) with a motor
  inertia ``motor_inertia_kg_m2`` and a speed loop; its time to 63 % is about
  ``MODEL_TIME_CONSTANT_S`` (the shipped file's fit). An identified extra lag T (beyond the
  thrust the allocator records) scales ``motor_inertia_kg_m2`` by (T_model + T) / T_model,
  which slows the speed loop (J_m / (K_t K_fb)) in proportion: a first-order reading of a
  model that is not first order, stated in the file.
- **Thrusters' gain**: no key of the robot folder takes it. The allocator's thruster model
  is also the simulator's plant, so a gain there would be inverted away; on the real robot
  a gain k belongs to the thrust column of ``hardware.yaml`` ``ardusub.t200`` (multiply the
  curve's thrusts by k). Reported, and written in the header of thrusters.yaml.
- **Joint friction**: the URDF's ``<dynamics damping="..." friction="..."/>`` of each joint
  (viscous N m s/rad, Coulomb N m): the standard place, read by URDF tools. This stack's
  model does not apply joint friction (docs/robots.md): recorded for the user and the
  hardware's tuning, no change to a simulation.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

from uvms_identify.actuators import Term
from uvms_identify.identify import Identification

#: The shipped thruster model's time to 63 % (s) (thrusters.yaml: J_m, K_fb fitted to it).
MODEL_TIME_CONSTANT_S = 0.020
_INERTIA = re.compile(r'^(\s*motor_inertia_kg_m2:\s*)([0-9.eE+-]+)(.*)$', re.MULTILINE)


def _line(term: Term) -> str:
    ci = '' if math.isnan(term.ci95) else f' +- {term.ci95:.3g}'
    return f'{term.name} = {term.value:.4g}{ci} {term.unit} ({term.status})'


def actuator_terms(result: Identification) -> list[Term]:
    """The thrusters' gain and lag, then the joints' friction."""
    terms = []
    if result.thrust is not None:
        terms += [result.thrust.gain, result.thrust.time_constant]
    return terms + list(result.joint_friction)


def write_thrusters(result: Identification, out: Path, header: list[str]) -> Path:
    """DIR/thrusters.yaml: the robot folder's, its motor inertia scaled by an identified lag."""
    source = result.robot.files.directory / 'thrusters.yaml'
    text = source.read_text(encoding='utf-8')
    lines = [f'# Thrusters of robot {result.robot.name}, from `uvms identify fit` '
             '(docs/identification.md).', *header]
    path_terms = result.thrust
    if path_terms is not None:
        lines += ['# Identified (the recorded thrust f makes k L_T[f](t - d) on the hull):',
                  f'#   {_line(path_terms.gain)}', f'#   {_line(path_terms.time_constant)}',
                  f'#   thrust delay d = {1000 * path_terms.delay_s:+.0f} ms (the recording '
                  "path's, no key)"]
        lag = path_terms.time_constant
        if lag.identified and lag.value > 0.0:
            factor = (MODEL_TIME_CONSTANT_S + lag.value) / MODEL_TIME_CONSTANT_S
            text, count = _INERTIA.subn(
                lambda m: (f'{m.group(1)}{float(m.group(2)) * factor:.4g}  # identified: x'
                           f'{factor:.3g} for {1000 * lag.value:.0f} ms more lag than the '
                           f'model (was {m.group(2)}){m.group(3)}'), text)
            lines.append(f'#   motor_inertia_kg_m2 scaled by {factor:.3g} '
                         f'({count} entry): time to 63 % about '
                         f'{1000 * (MODEL_TIME_CONSTANT_S + lag.value):.0f} ms')
        else:
            lines.append('#   motor_inertia_kg_m2 unchanged: no lag beyond the recorded '
                         'thrust identified')
        if path_terms.gain.identified:
            lines.append(f'#   gain: no key here (the model is also the plant); on the real '
                         f"robot multiply hardware.yaml's ardusub.t200 thrusts by "
                         f'{path_terms.gain.value:.4g}')
    path = out / 'thrusters.yaml'
    path.write_text('\n'.join(lines) + '\n' + text, encoding='utf-8')
    return path


def write_urdf(result: Identification, out: Path, header: list[str]) -> Path | None:
    """DIR/robot.urdf with ``<dynamics>`` per joint whose friction was identified.

    Returns:
        The file, or None when no joint's friction was identified (nothing to write).
    """
    by_joint: dict[str, dict[str, float]] = {}
    for term in result.joint_friction:
        if not term.identified:
            continue
        viscous = '_viscous_friction' in term.name
        joint = term.name.split('_viscous_friction' if viscous else '_coulomb_friction')[0]
        by_joint.setdefault(joint, {})['damping' if viscous else 'friction'] = term.value
    if not by_joint:
        return None
    text = result.robot.files.urdf.read_text(encoding='utf-8')
    for joint, values in by_joint.items():
        pattern = re.compile(r'(<joint name="' + re.escape(joint) + r'"[^>]*>.*?)(\s*</joint>)',
                             re.DOTALL)
        attributes = ' '.join(f'{k}="{v:.4g}"' for k, v in sorted(values.items()))
        element = f'\n    <dynamics {attributes}/>  <!-- identified: uvms identify fit -->'
        text = pattern.sub(lambda m, e=element: m.group(1) + e + m.group(2), text, count=1)
    body = '\n'.join(['Joint friction identified by `uvms identify fit` '
                      '(docs/identification.md): <dynamics damping (N m s/rad) friction '
                      '(N m)> per joint; the model does not apply it.',
                      *(f'     {line.lstrip("# ")}' for line in header),
                      *(f'     {_line(t)}' for t in result.joint_friction)])
    comment = '<!-- ' + body.replace('--', '- -') + '\n-->'  # no '--' inside a comment
    declaration = re.match(r'\s*<\?xml[^>]*\?>\s*', text)
    split = declaration.end() if declaration else 0
    path = out / 'robot.urdf'
    path.write_text(text[:split] + comment + '\n' + text[split:], encoding='utf-8')
    return path


def report_lines(result: Identification) -> list[str]:
    """The report's section on the actuators."""
    terms = actuator_terms(result)
    if not terms:
        return []
    lines = ['## Actuators', '',
             'Thrusters: the recorded thrust f makes k L_T[f](t - d) on the hull (gain k, '
             'first-order lag T, delay d), fitted with the hull terms; arm joints: the torque '
             "commanded minus the model's arm rows, fitted as viscous + Coulomb friction "
             '(docs/identification.md, "Actuators"). Robot folder: gain 1, no lag beyond the '
             'recorded thrust, no joint friction.', '',
             '| term | identified | 95 % CI | status |', '| --- | --- | --- | --- |']
    for term in terms:
        ci = 'n/a' if math.isnan(term.ci95) else f'+- {term.ci95:.3g}'
        lines.append(f'| {term.name} ({term.unit}) | {term.value:.4g} | {ci} | '
                     f'{term.status} |')
    if not result.joint_friction:
        lines += ['', 'Joint friction: no joint torques recorded (command/actuators '
                  'joint_torques): not fitted.']
    return [*lines, '']
