"""The renderer's own error."""

from emogen.errors import EmoGenError


class RenderError(EmoGenError):
    """No OpenGL context could be made, a shader failed to compile, or an image can't be written."""
