"""Campaigns: many accidents analysed and grouped by root cause (``rocas triage``)."""

from rocas.campaign.grouping import group_accidents, root_cause_keys, scores
from rocas.campaign.inputs import CampaignInput, collect_inputs
from rocas.campaign.triage import build_campaign, groups_signature, triage

__all__ = ["CampaignInput", "build_campaign", "collect_inputs", "group_accidents",
           "groups_signature", "root_cause_keys", "scores", "triage"]
