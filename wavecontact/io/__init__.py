"""Files: fields of a finite-element result for ParaView (meshio).

Nothing numerical imports this package; :mod:`meshio` is loaded only when
:mod:`wavecontact.io.fields` is.
"""

__all__ = ["read_fields", "write_fields"]


def __getattr__(name):  # lazy: keep ``import wavecontact.io`` cheap
    if name in __all__:
        from . import fields

        return getattr(fields, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
