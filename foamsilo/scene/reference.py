"""The scene-file reference (Markdown), generated from the scene model."""

from __future__ import annotations

import dataclasses
from typing import Any, Literal, get_args, get_origin, get_type_hints

from foamsilo.scene.model import Scene
from foamsilo.scene.schema import describe_range


def reference_markdown() -> str:
    """Scene-file reference (Markdown), generated from the dataclasses."""
    out = ["# Scene file reference", "", "Generated from `foamsilo/scene/model.py`. SI units.", ""]

    def table(cls: Any, prefix: str) -> None:
        hints = get_type_hints(cls)
        rows = []
        subs = []
        for f in dataclasses.fields(cls):
            typ = hints[f.name]
            if dataclasses.is_dataclass(typ):
                subs.append((typ, f"{prefix}{f.name}"))
                continue
            meta = f.metadata
            if get_origin(typ) is Literal:
                allowed = ", ".join(f"`{a}`" for a in get_args(typ))
            else:
                allowed = describe_range(meta) or "-"
            if f.default is not dataclasses.MISSING:
                if isinstance(f.default, bool):
                    default = f"`{str(f.default).lower()}`"
                else:
                    default = "-" if f.default in (None, "", ()) else f"`{f.default}`"
            else:
                default = "required"
            rows.append(
                f"| `{f.name}` | {meta.get('unit') or '-'} | {allowed} | {default} "
                f"| {meta.get('description', '')} |"
            )
        title = f"[{prefix[:-1]}]" if prefix else "top level"
        out.extend(
            [
                f"## {title}",
                "",
                "| key | unit | allowed | default | meaning |",
                "| --- | --- | --- | --- | --- |",
                *rows,
                "",
            ]
        )
        for sub, name in subs:
            table(sub, name + ".")

    table(Scene, "")
    return "\n".join(out)
