"""Semantic process plans (section 4 of the paper): a goal over symbolic objects, planned in STRIPS by
unified-planning and executed in the cell by binding each object to a recognised part."""

from sim.plans.execution import ActionOutcome, PlanResult, run_plan
from sim.plans.plan_file import Action, Destination, Goal, PlanObject, ProcessPlan, load_plan
from sim.plans.planning import Step, goal_places, solve, write_pddl

__all__ = ["Action", "ActionOutcome", "Destination", "Goal", "PlanObject", "PlanResult", "ProcessPlan", "Step",
           "goal_places", "load_plan", "run_plan", "solve", "write_pddl"]
