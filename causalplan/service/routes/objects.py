"""GET /v1/objects and GET /v1/objects/{id}: the catalog the service plans with."""

from __future__ import annotations

from fastapi import APIRouter

from causalplan.objects.model import AssemblyObject
from causalplan.service.deps import CatalogDep
from causalplan.service.schemas import (
    ConnectorOut,
    FitOut,
    MechanismOut,
    ObjectOut,
    ObjectPartOut,
    ObjectSummaryOut,
    PartOut,
    RequirementOut,
    error_responses,
)

router = APIRouter(prefix="/v1/objects", tags=["objects"], responses=error_responses(404))


def object_out(obj: AssemblyObject) -> ObjectOut:
    """Return the API view of a catalog object."""
    return ObjectOut(
        id=obj.id,
        name=obj.name,
        category=obj.category,
        goal=obj.goal,
        description=obj.description,
        base=obj.base,
        parts=[
            PartOut(
                id=part.id,
                name=part.name,
                connectors=[ConnectorOut(id=c.id, kind=c.kind, spec=c.spec) for c in part.connectors],
            )
            for part in obj.parts
        ],
        fits=[
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
        ],
        mechanism=MechanismOut(
            explanation=obj.mechanism_explanation,
            requires=[RequirementOut(any_of=list(r.any_of), says=r.says) for r in obj.mechanism],
        ),
    )


@router.get("", response_model=list[ObjectSummaryOut], summary="The catalog")
def list_objects(catalog: CatalogDep) -> list[ObjectSummaryOut]:
    """List the objects a model can be about: id, name, category, goal and parts."""
    return [
        ObjectSummaryOut(
            id=obj.id,
            name=obj.name,
            category=obj.category,
            goal=obj.goal,
            description=obj.description,
            parts=[ObjectPartOut(id=part.id, name=part.name) for part in obj.parts],
        )
        for obj in catalog.objects.values()
    ]


@router.get("/{object_id}", response_model=ObjectOut, summary="One catalog object")
def read_object(object_id: str, catalog: CatalogDep) -> ObjectOut:
    """Show one object: parts and connectors, the fits between them, and its true mechanism."""
    return object_out(catalog.get(object_id))
