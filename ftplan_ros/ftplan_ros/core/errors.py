"""The core's one exception type for bad input: it names the offending field."""


class InputError(ValueError):
    """Input the core cannot work with; `field` names where it is (e.g. `robot.link_lengths[1]`)."""

    def __init__(self, field: str, problem: str) -> None:
        super().__init__(f'{field}: {problem}')
        self.field = field
        self.problem = problem
