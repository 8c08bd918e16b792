"""Online control: clik's loop one tick at a time (:class:`Controller`)."""

from clik.control.controller import Controller
from clik.control.tick import VERDICTS, Tick

__all__ = ["VERDICTS", "Controller", "Tick"]
