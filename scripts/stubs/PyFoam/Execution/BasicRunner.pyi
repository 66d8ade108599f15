# Typing stub for PyFoam's runner: the solver thread and the line handler foamsilo overrides.
from typing import Any

from PyFoam.RunDictionary.SolutionDirectory import SolutionDirectory

class _FoamThread:
    cmdline: str
    threadPid: int
    def interrupt(self, pass_int: bool = ...) -> None: ...
    def join(self, timeout: float | None = ...) -> None: ...

class BasicRunner:
    dir: str
    run: _FoamThread
    def __init__(
        self,
        argv: list[str] | None = ...,
        silent: bool = ...,
        logname: str | None = ...,
        compressLog: bool = ...,
        lam: Any = ...,
        server: bool = ...,
        restart: bool = ...,
        noLog: bool = ...,
        logTail: int | None = ...,
        remark: str | None = ...,
        jobId: str | None = ...,
        parameters: dict[str, Any] | None = ...,
        writeState: bool = ...,
        echoCommandLine: str | None = ...,
    ) -> None: ...
    def start(self) -> dict[str, Any]: ...
    def lineHandle(self, line: str) -> None: ...
    def getSolutionDirectory(self, archive: str | None = ...) -> SolutionDirectory: ...
