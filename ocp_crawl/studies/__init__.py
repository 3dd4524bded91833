"""The paper's studies, their figures, the statement checks and ``reproduce``."""
