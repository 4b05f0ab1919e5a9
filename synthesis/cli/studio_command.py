"""``agrisynth studio``: the interactive design page (the studio extra), served on 127.0.0.1."""

from __future__ import annotations

import webbrowser
from pathlib import Path

import click
from rich.markup import escape

from synthesis.cli.options import NamedPath, WholeNumber
from synthesis.cli.views import Terminal, console
from synthesis.errors import AgrisynthError
from synthesis.runs.specs import spec_file
from synthesis.studio import missing_extra_text


@click.command("studio")
@click.argument("spec", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--out", type=NamedPath(file_okay=False, path_type=Path), default=Path("results/studio"),
              show_default=True, help="the one folder the page writes into (saved specs, solve runs)")
@click.option("--port", type=WholeNumber(min=0, max=65535), default=0, show_default=True,
              help="port on 127.0.0.1 (0: any free one)")
@click.option("--open", "open_browser", is_flag=True, help="open the page in the default browser")
def studio_command(spec: Path, out: Path, port: int, open_browser: bool) -> None:
    """An interactive design page for SPEC, served on 127.0.0.1 only (needs the `studio` extra).

    A slider per design variable; the mechanism, its path and every rule of `agrisynth check` redrawn as
    you drag (a coarse grid while dragging, the check's grid on release); solve from here (`agrisynth
    solve` with the page's values as start 0, in a worker process), save spec, reset, compare with the
    baseline. Prints the page's address (with its random token); Ctrl-C stops the server.
    """
    try:
        from synthesis.studio.server import Studio      # the studio extra: starlette and uvicorn, maybe missing
    except ImportError as exc:
        raise AgrisynthError(missing_extra_text(exc.name)) from None
    with Terminal() as terminal:
        spec = spec_file(spec, terminal)
    try:
        app = Studio(spec, out, port)
    except OSError as exc:
        raise AgrisynthError(f"--port {port}: cannot listen on 127.0.0.1 ({exc.strerror})") from None

    def listening() -> None:        # the address once the socket listens: a browser given it is answered
        console.print(f"agrisynth studio for {escape(str(spec))}: open\n  {app.url}\n"
                      f"writing into {escape(str(app.out))}/; Ctrl-C stops", soft_wrap=True)
        if open_browser:
            webbrowser.open(app.url)

    app.serve(on_listening=listening)
