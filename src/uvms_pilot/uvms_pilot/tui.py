"""The terminal UI of ``uvms pilot``: keys in, the live state on screen (prompt_toolkit).

Full screen; every key goes to the session as pressed (terminals report no releases: see
``uvms_pilot.keys``); the session publishes at the tick rate; the screen is redrawn at each
tick. Ctrl-C or Ctrl-Q leaves (the moving parts get one zero first).
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable

from uvms_pilot.command import GEARS
from uvms_pilot.link import LiveState
from uvms_pilot.session import PilotSession, describe_command

#: The key help under the state (uvms_pilot.keys has the layout).
HELP = (
    'vehicle  w/s surge   a/d sway   r/f heave up/down   q/e yaw left/right',
    'arm      i/k x+/x-   j/l y-/y+  u/o z up/down       jaw m open / n close',
    'gear     1 2 3 (25/50/100 %), - +    space STOP   h hold   t start task   c cancel task',
    'Ctrl-C quit',
)


def _value(value: float | None, text: str) -> str:
    return '-' if value is None else text.format(value)


def render(live: LiveState, session: PilotSession, title: str) -> str:
    """The screen: title, live state, command, task, diagnostics, note and key help."""
    velocity = ('-' if live.velocity_m_s is None
                else 'u {:+.2f} v {:+.2f} w {:+.2f} m/s'.format(*live.velocity_m_s))
    gears = ' '.join(f'[{g:.0%}]' if i == session.gear_index else f'{g:.0%}'
                     for i, g in enumerate(GEARS))
    lines = [
        f'{title}   mode: {live.mode or "-"}   gear: {gears}',
        '',
        f'depth {_value(live.depth_m, "{:.2f} m")}   heading '
        f'{_value(live.heading_deg, "{:.1f} deg")}   velocity {velocity}   force '
        f'{_value(live.force_n, "{:.1f} N")}',
        f'command: {describe_command(session.last_command)}',
        f'task: {live.task or "-"}',
        f'diagnostics: {live.diagnostics or "-"}',
        f'> {live.note or ""}',
        '',
        *HELP,
    ]
    return '\n'.join(lines) + '\n'


def run_tui(session: PilotSession, live: Callable[[], LiveState], rate_hz: float,
            title: str) -> None:
    """Run the full-screen UI until Ctrl-C / Ctrl-Q; publish ticks at rate_hz meanwhile."""
    from prompt_toolkit.application import Application
    from prompt_toolkit.key_binding import KeyBindings, KeyPressEvent
    from prompt_toolkit.layout import Layout, Window
    from prompt_toolkit.layout.controls import FormattedTextControl

    bindings = KeyBindings()

    @bindings.add('c-c')
    @bindings.add('c-q')
    def _quit(event: KeyPressEvent) -> None:
        event.app.exit()

    @bindings.add('<any>')
    def _key(event: KeyPressEvent) -> None:
        now = time.monotonic()
        for press in event.key_sequence:
            if len(press.data) == 1:
                session.press(press.data.lower(), now)

    control = FormattedTextControl(lambda: render(live(), session, title), focusable=True)
    app: Application[None] = Application(layout=Layout(Window(control)),
                                         key_bindings=bindings, full_screen=True)

    async def ticks() -> None:
        period_s = 1.0 / rate_hz
        next_s = time.monotonic()
        while True:
            session.tick(time.monotonic())
            app.invalidate()
            next_s = max(next_s + period_s, time.monotonic() - period_s)
            await asyncio.sleep(max(0.0, next_s - time.monotonic()))

    app.run(pre_run=lambda: app.create_background_task(ticks()))
