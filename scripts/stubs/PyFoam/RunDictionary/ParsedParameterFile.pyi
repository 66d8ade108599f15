# Typing stub for PyFoam's dictionary parser as foamsilo uses it.
from typing import Any

class ParsedParameterFile:
    content: Any
    header: dict[str, Any]
    def __init__(
        self,
        name: str,
        backup: bool = ...,
        debug: bool = ...,
        boundaryDict: bool = ...,
        listDict: bool = ...,
        listDictWithHeader: bool = ...,
        listLengthUnparsed: int | None = ...,
        preserveComments: bool = ...,
        noHeader: bool = ...,
        binaryMode: bool = ...,
        treatBinaryAsASCII: bool = ...,
        noBody: bool = ...,
        doMacroExpansion: bool = ...,
        dontRead: bool = ...,
        noVectorOrTensor: bool = ...,
        dictStack: Any = ...,
        createZipped: bool = ...,
        longListOutputThreshold: int = ...,
    ) -> None: ...
    def __getitem__(self, key: str) -> Any: ...
    def __setitem__(self, key: str, value: Any) -> None: ...
    def writeFile(self, content: Any = ...) -> None: ...

class ParsedBoundaryDict(ParsedParameterFile):
    def __init__(self, name: str, treatBinaryAsASCII: bool = ..., backup: bool = ...) -> None: ...
