"""GET /v1/objects and GET /v1/objects/{id}: the catalog the service plans with."""

from __future__ import annotations

from fastapi import APIRouter

from causalplan.objects.model import AssemblyObject
from causalplan.service.api.schemas.common import error_responses
from causalplan.service.api.schemas.objects import FitOut, MechanismOut, ObjectOut, ObjectSummaryOut, RequirementOut
from causalplan.service.deps import CatalogDep

router = APIRouter(prefix="/v1/objects", tags=["objects"], responses=error_responses(404))


def object_out(obj: AssemblyObject) -> ObjectOut:
    """Return the API view of a catalog object."""
    fits = [
        FitOut(
            id=fit.id,
            primitive=fit.primitive,
            moving=f"{fit.moving_part}.{fit.moving_connector}",
            fixed=f"{fit.fixed_part}.{fit.fixed_connector}",
            probability=fit.probability,
            blocks=[".".join(block) for block in fit.blocks],
            text=obj.step_text(fit),
        )
        for fit in obj.fits
    ]
    mechanism = MechanismOut(
        explanation=obj.mechanism_explanation,
        requires=[RequirementOut.model_validate(requirement, from_attributes=True) for requirement in obj.mechanism],
    )
    summary = ObjectSummaryOut.model_validate(obj, from_attributes=True)
    return ObjectOut.model_validate(
        {
            **dict(summary),
            "base": obj.base,
            "parts": obj.parts,
            "fits": fits,
            "mechanism": mechanism,
            "faults": obj.faults,
            "fault_priors": obj.fault_priors,
        },
        from_attributes=True,
    )


@router.get("", response_model=list[ObjectSummaryOut], summary="The catalog")
def list_objects(catalog: CatalogDep) -> list[ObjectSummaryOut]:
    """List the objects a model can be about: id, name, category, goal and parts."""
    return [ObjectSummaryOut.model_validate(obj, from_attributes=True) for obj in catalog.objects.values()]


@router.get("/{object_id}", response_model=ObjectOut, summary="One catalog object")
def read_object(object_id: str, catalog: CatalogDep) -> ObjectOut:
    """Show one object: parts and connectors, the fits between them, and its true mechanism."""
    return object_out(catalog.get(object_id))
