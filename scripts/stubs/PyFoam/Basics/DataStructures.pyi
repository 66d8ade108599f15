# Typing stub for the PyFoam data structures foamsilo reads and writes.
from typing import Any

class DictProxy(dict[str, Any]):
    def __init__(self) -> None: ...

class FixedLength:
    vals: list[Any]
    def __init__(self, vals: list[Any]) -> None: ...
    def __iter__(self) -> Any: ...
    def __getitem__(self, key: int) -> Any: ...

class Vector(FixedLength):
    def __init__(self, x: Any, y: Any, z: Any) -> None: ...

class UnparsedList:
    length: int
    data: str
    def __init__(self, lngth: int, data: str) -> None: ...

class BinaryList(UnparsedList): ...

class Field:
    val: Any
    name: str | None
    uniform: bool
    def __init__(self, val: Any, name: str | None = ..., length: int | None = ...) -> None: ...
