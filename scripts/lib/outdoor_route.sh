# Sourced by run_experiments.sh and outdoor_localisation.sh: the outdoor route of the reports,
# 2.2 km of five straights joined by four tight turns (left, left, right, right), as
# dataset_simulator arguments.
MRVS_OUTDOOR_ROUTE=(--profile outdoor --set "route.straight_lengths_m=[500,400,500,400,300]"
                    --set "route.turn_directions=[-1,-1,1,1]" --set "route.turn_radii_m=[18,18,18,18]")
