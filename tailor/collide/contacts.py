"""Body contacts handed from a collision response to the next implicit step.

A :class:`Contacts` is what the body's response (:meth:`tailor.collide.BodyCollider.respond`) and
its landing prediction find, and what the implicit integrator holds within its solve (Baraff &
Witkin 1998's velocity constraints): the one record that travels between the two, by value.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Contacts", "NO_CONTACTS"]


@dataclass(frozen=True, slots=True)
class Contacts:
    """Body contacts to hold during the next implicit step.

    Vertex ``ids[k]`` ends the step with velocity ``normal_velocity[k]`` along the unit
    ``normals[k]`` (the body's own normal velocity: no approach), free in the tangent plane but
    for friction: ``friction[k]`` (μ) times ``normal_force[k]`` [N], the body's push on it over
    the step that found the contact, resists its tangent motion relative to ``body_velocity[k]``
    (Eq. 14's Coulomb friction, regularised and held inside the implicit solve's matrix). A contact
    without a normal force (a predicted landing) slides freely in the step it lands.
    ``vertex_count`` is the size of the model they were found for; they are ignored on another.
    """

    ids: np.ndarray
    normals: np.ndarray
    normal_velocity: np.ndarray
    vertex_count: int
    body_velocity: np.ndarray | None = None
    friction: np.ndarray | None = None
    normal_force: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.ids)

    def valid_for(self, model) -> bool:
        """Whether they were found for ``model``'s numbering of the vertices (and hold any)."""
        return self.vertex_count == model.vertex_count and len(self.ids) > 0


NO_CONTACTS = Contacts(np.zeros(0, np.intp), np.zeros((0, 3)), np.zeros(0), 0)
"""No contact at all (valid for no model)."""
