"""``swm convert`` (upstream 0.1.1) and ``swm preview`` (upstream's main): a dataset to another
format, and a first look at its episodes as videos."""

from __future__ import annotations

from typing import Annotated

import typer


def convert_cmd(
    name: Annotated[str, typer.Argument(help="Source dataset: a name in the cache or a path.", show_default=False)],
    output: Annotated[
        str | None,
        typer.Argument(help="Output dataset name, beside the source. Default: NAME-FORMAT.", show_default=False),
    ] = None,
    dest_format: Annotated[str, typer.Option("--dest-format", "-f", help="Destination format.")] = "video",
    source_format: Annotated[
        str | None, typer.Option("--source-format", help="Force the source format (skip detection).")
    ] = None,
) -> None:
    """Convert a dataset to another format (hdf5, lance, video, folder), episode by episode."""
    from ..data.format import get_format
    from ..data.utils import convert, resolve_dataset

    fmt = get_format(dest_format)  # an unknown format fails before anything is read
    source = resolve_dataset(name, who="swm convert")
    dest = source.parent / (output if output is not None else f"{source.stem}-{fmt.name}")
    typer.echo(f"Converting {source.name} -> {fmt.name} as {dest.name}")
    written = convert(source, dest, dest_format=fmt.name, source_format=source_format)
    typer.echo(f"Done. Output: {written}")


def preview_cmd(
    name: Annotated[str, typer.Argument(help="Dataset: a name in the cache or a path.", show_default=False)],
    n: Annotated[int, typer.Option("-n", help="Episodes to draw (when --episodes is not given).")] = 4,
    episodes: Annotated[
        str | None, typer.Option("--episodes", help="Episodes to show, comma-separated (e.g. 0,3,7).")
    ] = None,
    out: Annotated[
        str | None, typer.Option("--out", help="Folder of the videos. Default: $STABLEWM_HOME/previews/NAME.")
    ] = None,
    fps: Annotated[int, typer.Option("--fps", help="Frames per second.")] = 10,
    seed: Annotated[int, typer.Option("--seed", help="Seed of the episode draw.")] = 0,
) -> None:
    """Write one MP4 per episode of a dataset, its image columns side by side."""
    from ..data.video import preview_dataset
    from ..errors import ConfigError

    chosen = None
    if episodes is not None:
        try:
            chosen = [int(e) for e in episodes.split(",") if e.strip()]
        except ValueError:
            raise ConfigError(f"--episodes requires comma-separated integers such as 0,3,7, got {episodes!r}") from None
    paths = preview_dataset(name, episodes=chosen, n=n, out=out, fps=fps, seed=seed)
    for path in paths:
        typer.echo(str(path))
